// The one PLY header parser (formats/ply/ply_format.h), read two ways: by
// the stream, strictly, each refusal naming its line; and as the importer
// reads it, for the checks before the importer, letting be the lines the
// importer lets be and refusing what it misreads.
#include <gtest/gtest.h>

#include <string>

#include "core/errors.h"
#include "formats/ply/ply_format.h"

namespace opsila {
namespace {

using ply::Reading;

const std::string kHeader =
    "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kBody = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

// The error parse_header gives for a file of `bytes`, "" when it reads its header.
std::string error_of(const std::string& bytes, Reading how) {
  try {
    ply::parse_header(bytes, bytes.size(), "f.ply", how);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string refusal(const std::string& header, Reading how) { return error_of(header + kBody, how); }

// kHeader with its line `from` replaced by `to`.
std::string with(const std::string& from, const std::string& to) {
  std::string h = kHeader;
  const std::size_t at = h.find(from);
  return at == std::string::npos ? h : h.replace(at, from.size(), to);
}

TEST(PlyHeader, BothReadingsReadAPlainHeaderAlike) {
  for (Reading how : {Reading::stream, Reading::importer}) {
    const std::string bytes = kHeader + kBody;
    const ply::Header h = ply::parse_header(bytes, bytes.size(), "f.ply", how);
    EXPECT_EQ(h.format, ply::Format::ascii);
    ASSERT_EQ(h.elements.size(), 2u);
    EXPECT_EQ(h.elements[0].name, "vertex");
    EXPECT_EQ(h.elements[0].count, 3u);
    EXPECT_EQ(h.elements[0].line, 4);
    EXPECT_EQ(h.elements[1].properties.at(0).count, ply::Type::uint8);
    EXPECT_TRUE(h.elements[1].properties.at(0).list);
    EXPECT_EQ(h.body, kHeader.size());
    EXPECT_EQ(h.lines, 10);
    EXPECT_EQ(ply::stream_refusal(h), "");
  }
}

// The stream refuses on the line at fault; the importer's reading lets an
// unknown line be and judges the rest after the header, in its own words.
TEST(PlyHeader, EachReadingRefusesInItsOwnWords) {
  struct Case {
    std::string header, stream, importer;
  };
  const Case cases[] = {
      {with("comment", "made"), "f.ply:3: PLY header: unknown line 'made'", ""},
      {with("comment made by hand\n", "\n"), "f.ply:3: PLY header: empty line", ""},
      {with("element face 1", "element vertex 1"), "f.ply:8: PLY header: the element 'vertex' is declared twice",
       "f.ply: PLY header declares the element 'vertex' twice"},
      {with("element vertex 3\n", "property float w\nelement vertex 3\n"),
       "f.ply:4: PLY header: a property before any element", "f.ply: PLY header has a property before any element"},
      {with("property list uchar", "property list uc|"), "f.ply:9: PLY header: unknown property type 'uc|'",
       "f.ply: PLY 'face' element: a property of unknown type"},
      {with("ascii 1.0", "asci 1.0"),
       "f.ply:2: PLY header: format 'asci' (ascii, binary_little_endian or binary_big_endian)",
       "f.ply: PLY format 'asci' (ascii, binary_little_endian or binary_big_endian)"},
      // A broken first format line is not mended by a later good one (the
      // importer allocated 4 GB on such a file: found by fuzz_model).
      {with("ascii 1.0\n", "asci 1.0\nformat ascii 1.0\n"),
       "f.ply:2: PLY header: format 'asci' (ascii, binary_little_endian or binary_big_endian)",
       "f.ply: PLY format 'asci' (ascii, binary_little_endian or binary_big_endian)"},
      {with("ascii 1.0", "ascii 2.0"), "f.ply:2: PLY header: 'format TYPE 1.0' expected once",
       "f.ply: PLY format version '2.0' (1.0 expected)"},
      {with("ascii 1.0", "ascii"), "f.ply:2: PLY header: 'format TYPE 1.0' expected once",
       "f.ply: PLY format version '' (1.0 expected)"},
      {with("format ascii 1.0\n", ""), "f.ply:3: PLY header: an element before the format line",
       "f.ply: PLY format '' (ascii, binary_little_endian or binary_big_endian)"},
      {with("element vertex 3", "element vertex 3000"), "",
       "f.ply: PLY header asks for 3000 'vertex' elements, more than a file of " +
           std::to_string(kHeader.size() + 3 + kBody.size()) + " bytes can hold"},
      {with("ply\n", "PLY\n"), "f.ply: not PLY (a PLY file starts with the line 'ply')",
       "f.ply: not PLY (a PLY file starts with the line 'ply')"},
      {with("end_header", "end"), "f.ply:10: PLY header: unknown line 'end'",
       "f.ply: PLY header without an 'end_header' line (truncated or not PLY)"},
      {with("end_header\n", "end_header x\n"), "", "f.ply: PLY 'end_header' not followed by a line break"},
      // The importer read one of the two; both readings refuse it now.
      {with("property float y\n", "property float y\nproperty float x\n"),
       "f.ply: PLY 'vertex' element: the property 'x' is declared twice",
       "f.ply: PLY 'vertex' element: the property 'x' is declared twice"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.header);
    EXPECT_EQ(refusal(c.header, Reading::stream), c.stream);
    EXPECT_EQ(refusal(c.header, Reading::importer), c.importer);
  }
}

// A file without a line break: the stream finds no header's end, the
// importer's reading no 'ply' line.
TEST(PlyHeader, AFileOfOneUnendedLine) {
  EXPECT_EQ(error_of("ply", Reading::stream), "f.ply: PLY header without an 'end_header' line (truncated or not PLY)");
  EXPECT_EQ(error_of("ply", Reading::importer), "f.ply: not PLY (a PLY file starts with the line 'ply')");
}

// Lines that end with a lone CR (old Mac text) are named as such by both
// readings: the file had been "not PLY", or without an 'end_header'.
TEST(PlyHeader, LinesEndingInALoneCrAreNamed) {
  std::string cr = kHeader + kBody;
  for (char& c : cr)
    if (c == '\n') c = '\r';
  const std::string why = "f.ply: its lines end with a lone CR (old Mac text): PLY lines end with LF or CR LF";
  EXPECT_EQ(error_of(cr, Reading::stream), why);
  EXPECT_EQ(error_of(cr, Reading::importer), why);
  std::string crlf;
  for (char c : kHeader) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  EXPECT_EQ(refusal(crlf, Reading::stream), "");
  EXPECT_EQ(refusal(crlf, Reading::importer), "");
}

}  // namespace
}  // namespace opsila
