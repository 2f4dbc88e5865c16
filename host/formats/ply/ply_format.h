// What a PLY file is: its header, read by one parser for the PLY stream
// (ply_window.cpp) and for the checks before the importer (ply_checks.cpp),
// and the reading of its body in bounded blocks (ply_header.cpp,
// ply_body.cpp).
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace opsila {
namespace ply {

// unknown: a type name the format does not have (the importer's reading
// judges it after the header; the stream's refuses it on its line).
enum class Type { int8, uint8, int16, uint16, int32, uint32, float32, float64, unknown };

// Bytes of a value of type t in a binary body (0 for unknown).
int type_bytes(Type t);
// Whether v is a value of the integer type t (never for a float type).
bool fits_type(std::int64_t v, Type t);

struct Property {
  std::string name;
  Type type = Type::float32;  // a list's items
  bool list = false;
  Type count = Type::uint8;   // a list's count
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  int line = 0;  // of its 'element' line
};

enum class Format { ascii, little_endian, big_endian };

struct Header {
  Format format = Format::ascii;
  std::string format_name;            // as the first 'format' line gives it
  std::string format_version;         // its version (PLY knows only 1.0)
  std::vector<Element> elements;
  std::vector<std::string> comments;  // 'comment' and 'obj_info' lines
  std::uint64_t body = 0;             // byte offset of the body
  int lines = 0;                      // of the header
  std::uint64_t file_bytes = 0;
};

// Who reads a header, and so what it may hold:
// - stream: strictly 'ply', 'format' (ascii, binary_little_endian,
//   binary_big_endian, 1.0), 'comment', 'obj_info', 'element', 'property'
//   (scalar or list), 'end_header'; any other line is an error naming it.
// - importer: as the importer reads it (lines it does not know are let
//   be), refusing what it misreads: a header without an 'end_header' line
//   of its own, an element declared twice, a property before any element,
//   more elements than the file can hold, unknown types or formats, a
//   format version other than 1.0.
// Each error is one InputError naming `path` (and, for the stream, the line).
enum class Reading { stream, importer };

// The header at the start of `bytes` (at least the header; the whole file
// for the importer's reading) of a file of file_bytes.
Header parse_header(const std::string& bytes, std::uint64_t file_bytes, const std::string& path, Reading how);

// The header of the file `path`, as the stream reads it; from `bytes`, the
// whole file in memory, when given (a model read from memory, fuzz_model).
Header read_header(const std::string& path, const std::string* bytes = nullptr);

// The checks before the importer reads the PLY file `bytes` (named `name`):
// its header (Reading::importer), a body that holds every element the
// header counts (text or binary), every vertex a face uses finite (text),
// and faces at all.
void check_ply(const std::string& bytes, const std::string& name);

// Whether the importer reads an element of this name by its header count:
// it takes another's count from its name ("range_grid" is 0 of them).
bool importer_knows(const std::string& element);

// The error for data past the last element `last` of a PLY file: at
// `line` (a text file) or at `byte` of the file (a binary one). Both readers
// had dropped a face past the header's count without a word.
[[noreturn]] void data_past_elements(const std::string& name, const Element& last, bool text, std::uint64_t where);

// Whether the header declares a 'tristrips' element.
bool has_strips(const Header& h);

// Why the stream cannot read `h` exactly as the importer does ("" when it
// can): the importer path is then used.
std::string stream_refusal(const Header& h);

// A value as the importer holds it (a 32-bit integer, signed or not, or
// the float or double read).
struct Value {
  std::int64_t i = 0;  // integer types
  double d = 0;        // float types
  Type type = Type::int32;
  float as_float() const;
  bool is_integer() const { return type != Type::float32 && type != Type::float64; }
};

// The body read in blocks of about block_bytes; every value is checked as
// read (a truncated body, a word that is not a number), errors naming the
// file and the element with its line (ascii) or byte offset (binary).
class Body {
 public:
  Body(const std::string& path, const Header& h, std::size_t block_bytes, const std::string* bytes = nullptr);
  ~Body();
  Body(const Body&) = delete;
  Body& operator=(const Body&) = delete;
  // The next value of element `e`'s instance `i` (0-based), of type t.
  Value next(Type t, const Element& e, std::uint64_t i);
  // Ascii: the end of an element's line (nothing else may follow on it).
  void end_of_instance(const Element& e, std::uint64_t i);
  // After the last element `last`: nothing but blank lines (binary:
  // nothing at all), or one error naming where the rest starts.
  void end_of_data(const Element& last);
  // Where the reading is, for messages: "line N" or "byte N".
  std::string where() const;
  // One error naming the file, the element and where it is read.
  [[noreturn]] void fail(const Element& e, std::uint64_t i, const std::string& what) const;

 private:
  bool fill(std::size_t need);
  std::string word(const Element& e, std::uint64_t i);

  std::string path_;
  Format format_;
  std::FILE* file_ = nullptr;
  std::size_t block_;
  std::vector<char> buf_;
  std::size_t at_ = 0, end_ = 0;  // buf_[at_, end_) not read yet
  std::uint64_t consumed_ = 0;    // file offset of buf_[0]
  long long line_ = 0;
  bool eof_ = false;
};

}  // namespace ply
}  // namespace opsila
