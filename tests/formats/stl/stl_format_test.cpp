// What an STL file is (formats/stl/stl_format.h): binary or text as the
// importer takes it, its facet count and header colours, one shape for the
// checks before the importer and for the stream's refusals.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdint>
#include <string>

#include "core/errors.h"
#include "formats/stl/stl_format.h"

namespace opsila {
namespace {

// An 80-byte header of `text`, the count, and `facets` records of zeros.
std::string binary(const std::string& text, std::uint32_t count, std::uint32_t facets) {
  std::string out = text;
  out.resize(80, ' ');
  for (int k = 0; k < 4; ++k) out += char(count >> (8 * k) & 0xff);
  return out + std::string(50 * std::size_t(facets), '\0');
}

std::string check_error(const std::string& bytes) {
  try {
    stl::check_stl(bytes, "f.stl");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(StlFormat, ABinaryFileIsTheSizeItsCountSays) {
  const std::string bytes = binary("solid but binary", 2, 2);  // "solid" too: the size decides
  const stl::Shape s = stl::shape_of(bytes, bytes.size());
  EXPECT_TRUE(s.exact);
  EXPECT_TRUE(s.solid);
  EXPECT_FALSE(s.text());
  EXPECT_EQ(s.facets, 2u);
  EXPECT_EQ(stl::stream_refusal(s), "");
  EXPECT_EQ(check_error(bytes), "");
}

TEST(StlFormat, OtherSizesAreTextOrATruncatedBinary) {
  const std::string text = "solid t\nendsolid t\n";
  EXPECT_TRUE(stl::shape_of(text, text.size()).text());
  EXPECT_EQ(stl::stream_refusal(stl::shape_of(text, text.size())), "it is shorter than a binary STL's 84-byte header");
  const std::string padded = binary("solid t", 1, 1) + "\n";
  EXPECT_EQ(stl::stream_refusal(stl::shape_of(padded, padded.size())), "an ASCII STL");
  const std::string cut = binary("made by a test", 3, 2);
  EXPECT_EQ(stl::stream_refusal(stl::shape_of(cut, cut.size())),
            "its size, 184 bytes, is not 84 + 50 x the 3 facets its header counts");
  EXPECT_EQ(check_error(cut), "f.stl: binary STL header counts 3 facets; the file holds 2 (truncated file)");
  EXPECT_EQ(check_error("no"), "f.stl: binary STL shorter than its 84-byte header (truncated file)");
}

// What the importer misread or named in its own words: data past a binary
// file's facets ("Failed to determine STL storage representation"), a
// binary header starting with "solid" read as text, UTF-16 text read as a
// binary of two million facets.
TEST(StlFormat, WhatTheImporterWouldMisreadIsNamed) {
  EXPECT_EQ(check_error(binary("made by a test", 1, 2)),
            "f.stl: binary STL: its size, 184 bytes, is not 84 + 50 x the 1 facets its header counts (data past its "
            "facets)");
  EXPECT_EQ(check_error(binary("solid but binary", 1, 2)),
            "f.stl: binary STL: its size, 184 bytes, is not 84 + 50 x the 1 facets its header counts (data past its "
            "facets)");
  EXPECT_EQ(check_error(binary("solid but binary", 3, 2)),
            "f.stl: binary STL header counts 3 facets; the file holds 2 (truncated file)");
  const std::string utf16 = std::string("\xff\xfes\0o\0l\0i\0d\0 \0t\0\n\0", 18);
  EXPECT_EQ(check_error(utf16), "f.stl: UTF-16 text: a text STL is ASCII (save it as such)");
  EXPECT_EQ(check_error(utf16.substr(2)), "f.stl: UTF-16 text: a text STL is ASCII (save it as such)");
}

// Keywords in upper case (some old exporters write them): the importer
// reads lower case only, and had taken "SOLID" for a binary header of a
// billion facets, or dropped upper-case facets and said "no facets".
TEST(StlFormat, UpperCaseKeywordsAreNamedWithTheirLine) {
  const std::string lower =
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
      "endsolid t\n";
  EXPECT_EQ(check_error(lower), "");
  std::string upper = lower;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  EXPECT_EQ(check_error(upper), "f.stl:1: STL keyword 'SOLID' is not in lower case: the importer reads 'solid' only");
  EXPECT_EQ(check_error("solid t\nFacet normal 0 0 1\n" + lower.substr(27)),
            "f.stl:2: STL keyword 'Facet' is not in lower case: the importer reads 'facet' only");
  EXPECT_EQ(check_error(lower.substr(0, lower.size() - 11) + "ENDSOLID t\n"),
            "f.stl:9: STL keyword 'ENDSOLID' is not in lower case: the importer reads 'endsolid' only");
  // A solid's name is any text; a binary header in capitals is a binary's.
  EXPECT_EQ(check_error("solid VERTEX\n" + lower.substr(8)), "");
  EXPECT_EQ(check_error(binary("SOLID made by a test", 1, 1)), "");
}

TEST(StlFormat, HeaderColoursAndEmptyFilesAreTheImportersToRead) {
  const std::string empty = binary("made by a test", 0, 0);
  EXPECT_EQ(stl::stream_refusal(stl::shape_of(empty, empty.size())), "its header counts no facets");
  const std::string coloured = binary("made by Magics COLOR=abcd", 1, 1);
  const stl::Shape s = stl::shape_of(coloured, coloured.size());
  EXPECT_EQ(s.colours, "COLOR=");
  EXPECT_EQ(stl::stream_refusal(s), "its header names Materialise colours (COLOR=)");
  // Only a name that starts in the 80 bytes of text counts.
  std::string late = binary("", 1, 1);
  late.replace(76, 9, "MATERIAL=");
  EXPECT_EQ(stl::shape_of(late, late.size()).colours, "MATERIAL=");
  late = binary("", 1, 1);
  late.replace(82, 6, "COLOR=");
  EXPECT_EQ(stl::shape_of(late, late.size()).colours, "");
}

}  // namespace
}  // namespace opsila
