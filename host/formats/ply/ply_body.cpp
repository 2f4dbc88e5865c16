// A PLY body read in bounded blocks, value after value, each checked as
// read. Ascii words are read as the importer reads them (its own number
// parsers, assimp/fast_atof.h), so the values are bit for bit its values.
#ifdef OPSILA_HAVE_ASSIMP
#include <stdio.h>  // fmemopen

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <assimp/fast_atof.h>

#include "core/errors.h"
#include "formats/ply/ply_format.h"

namespace opsila {
namespace ply {

namespace {

bool is_signed(Type t) { return t == Type::int8 || t == Type::int16 || t == Type::int32; }

bool blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// What the importer's number reader throws on a word that is not a number
// (its own exception type is not exported by the library).
struct NotANumber : std::runtime_error {
  template <class... Parts>
  explicit NotANumber(Parts&&...) : std::runtime_error("not a number") {}
};

}  // namespace

float Value::as_float() const {
  if (type == Type::float32 || type == Type::float64) return static_cast<float>(d);
  return is_signed(type) ? static_cast<float>(static_cast<std::int32_t>(i)) : static_cast<float>(static_cast<std::uint32_t>(i));
}

Body::Body(const std::string& path, const Header& h, std::size_t block_bytes, const std::string* bytes)
    : path_(path), format_(h.format), block_(std::max<std::size_t>(block_bytes, 1)), line_(h.lines) {
  // A file in memory holds its header, so it is never empty (which fmemopen refuses).
  file_ = bytes ? ::fmemopen(const_cast<char*>(bytes->data()), bytes->size(), "rb") : std::fopen(path.c_str(), "rb");
  if (!file_ || std::fseek(file_, static_cast<long>(h.body), SEEK_SET) != 0)
    throw InputError(path + ": cannot read: " + std::strerror(errno));
  consumed_ = h.body;
}

Body::~Body() {
  if (file_) std::fclose(file_);
}

// At least `need` bytes not read yet in the buffer, unless the file ends.
bool Body::fill(std::size_t need) {
  while (end_ - at_ < need && !eof_) {
    if (at_ > 0) {  // keep only what is not read yet
      std::memmove(buf_.data(), buf_.data() + at_, end_ - at_);
      consumed_ += at_;
      end_ -= at_;
      at_ = 0;
    }
    const std::size_t want = std::max(block_, need);
    if (buf_.size() < end_ + want) buf_.resize(end_ + want);
    const std::size_t got = std::fread(buf_.data() + end_, 1, want, file_);
    if (got < want && std::ferror(file_)) throw InputError(path_ + ": cannot read: " + std::strerror(errno));
    eof_ = got < want;
    end_ += got;
  }
  return end_ - at_ >= need;
}

std::string Body::where() const {
  return format_ == Format::ascii ? "line " + std::to_string(line_ + 1) : "byte " + std::to_string(consumed_ + at_);
}

void Body::fail(const Element& e, std::uint64_t i, const std::string& what) const {
  const std::string element = "PLY '" + e.name + "' element " + std::to_string(i + 1) + " of " + std::to_string(e.count);
  if (format_ == Format::ascii) throw InputError(path_ + ":" + std::to_string(line_ + 1) + ": " + element + ": " + what);
  throw InputError(path_ + ": " + element + " at byte " + std::to_string(consumed_ + at_) + ": " + what);
}

// The next word on the instance's line.
std::string Body::word(const Element& e, std::uint64_t i) {
  for (;;) {
    if (at_ == end_ && !fill(1)) fail(e, i, "the file ends early (truncated): fewer values than the header says");
    if (!blank(buf_[at_])) break;
    ++at_;
  }
  if (buf_[at_] == '\n') fail(e, i, "fewer values on the line than the header's properties");
  std::size_t n = 0;
  for (;;) {
    if (at_ + n == end_ && !fill(n + 1)) break;
    const char c = buf_[at_ + n];
    if (blank(c) || c == '\n') break;
    if (++n > 64) fail(e, i, "a word of more than 64 characters is not a number");
  }
  std::string w(buf_.data() + at_, n);
  at_ += n;
  return w;
}

Value Body::next(Type t, const Element& e, std::uint64_t i) {
  Value v;
  v.type = t;
  if (format_ != Format::ascii) {
    const int n = type_bytes(t);
    if (!fill(std::size_t(n))) fail(e, i, "the file ends early (truncated)");
    unsigned char b[8];
    for (int k = 0; k < n; ++k)
      b[k] = static_cast<unsigned char>(buf_[at_ + std::size_t(format_ == Format::big_endian ? n - 1 - k : k)]);
    at_ += std::size_t(n);
    std::uint64_t bits = 0;
    for (int k = n; k-- > 0;) bits = bits << 8 | b[k];
    switch (t) {
      case Type::int8: v.i = static_cast<std::int8_t>(bits); break;
      case Type::int16: v.i = static_cast<std::int16_t>(bits); break;
      case Type::int32: v.i = static_cast<std::int32_t>(bits); break;
      case Type::float32: { float f; std::uint32_t u = std::uint32_t(bits); std::memcpy(&f, &u, 4); v.d = f; break; }
      case Type::float64: std::memcpy(&v.d, &bits, 8); break;
      default: v.i = static_cast<std::int64_t>(bits);
    }
    return v;
  }
  const std::string w = word(e, i);
  const char* end = w.c_str();
  try {
    if (t == Type::float32) {
      float f = 0;
      end = Assimp::fast_atoreal_move<float, NotANumber>(w.c_str(), f);
      v.d = f;
    } else if (t == Type::float64) {
      end = Assimp::fast_atoreal_move<double, NotANumber>(w.c_str(), v.d);
    } else if (w.size() <= 11 && w.find_first_of("0123456789") != std::string::npos) {
      if (is_signed(t)) v.i = Assimp::strtol10(w.c_str(), &end);
      else v.i = Assimp::strtoul10(w.c_str(), &end);
      // The importer's readers wrap past 32 bits (99999999999 read as
      // 1215752191): such a word is no number of the type.
      if (std::strtoll(w.c_str(), nullptr, 10) != v.i) end = w.c_str();
    }
  } catch (const std::runtime_error&) {
    end = w.c_str();
  }
  if (end != w.c_str() + w.size() || (v.is_integer() && !fits_type(v.i, t)))
    fail(e, i, "'" + w + "' is not a number of its property's type");
  return v;
}

void Body::end_of_instance(const Element& e, std::uint64_t i) {
  if (format_ != Format::ascii) return;
  for (;;) {
    if (at_ == end_ && !fill(1)) return;  // the last line may lack its line break
    const char c = buf_[at_];
    if (c == '\n') break;
    if (!blank(c)) fail(e, i, "more values on the line than the header's properties");
    ++at_;
  }
  ++at_;
  ++line_;
}

void Body::end_of_data(const Element& last) {
  for (;;) {
    if (at_ == end_ && !fill(1)) return;
    const char c = buf_[at_];
    if (format_ != Format::ascii || !(blank(c) || c == '\n')) break;
    if (c == '\n') ++line_;
    ++at_;
  }
  data_past_elements(path_, last, format_ == Format::ascii,
                     format_ == Format::ascii ? std::uint64_t(line_ + 1) : consumed_ + at_);
}

}  // namespace ply
}  // namespace opsila
#endif
