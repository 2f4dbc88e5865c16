// The checks of a PLY file before the importer reads it (ply_format.h):
// its header as the importer reads it, then a body that holds what the
// header counts.
#include <algorithm>
#include <string_view>
#include <unordered_map>

#include "core/errors.h"
#include "core/util.h"
#include "formats/common/model_words.h"
#include "formats/ply/ply_format.h"

namespace opsila {
namespace ply {

using namespace model_words;

namespace {

[[noreturn]] void bad_count(const std::string& name, const Element& e, std::uint64_t i, const std::string& why) {
  throw InputError(name + ": PLY '" + e.name + "' element " + std::to_string(i + 1) + " of " +
                   std::to_string(e.count) + ": " + why);
}

[[noreturn]] void truncated(const std::string& name, const Element& e, std::uint64_t i) {
  throw InputError(name + ": PLY data ends early: '" + e.name + "' element " + std::to_string(i + 1) + " of " +
                   std::to_string(e.count) + " is missing or incomplete (truncated file)");
}

// Whether the importer reads every element the header counts, so that
// data past them is no element's (an element it does not know leaves its
// lines to the end: those are warned of as not read).
bool every_count_read(const Header& h) {
  for (const Element& e : h.elements)
    if (!importer_knows(e.name)) return false;
  return !h.elements.empty();
}

// The importer's next line (its stream buffer's): a line ends at '\r',
// '\n', NUL or '\f' (so a NUL splits a line in two); one that starts at
// such a byte first skips past the next '\n' (a "\r\n" ending, or one
// empty line). `line` is the file's line at `at`; `text_line` gets the
// line `text` is on, for messages.
bool next_line(std::string_view data, std::size_t& at, std::string_view& text, std::uint64_t& line,
               std::uint64_t& text_line) {
  const auto ends = [](char c) { return c == '\r' || c == '\n' || c == '\0' || c == '\f'; };
  if (at >= data.size()) return false;
  if (ends(data[at])) {
    const std::size_t lf = data.find('\n', at);
    if (lf == std::string_view::npos || lf + 1 >= data.size()) return false;
    line += 1, at = lf + 1;
  }
  const std::size_t start = at;
  text_line = line;
  while (at < data.size() && !ends(data[at])) ++at;
  text = data.substr(start, at - start);
  if (at < data.size() && data[at] == '\n') ++line;
  ++at;
  return true;
}

// The text data as the importer reads it: an element's instance from one
// line (next_line), then the next line, so an element without
// properties still takes a line each (found by fuzz_model: read as taking
// none, the face lists' counts came from other lines than the importer's,
// which asked for 24 GB). Every property one word of its line, a list its
// count and that many. A vertex whose x, y or z is not finite in floats
// (as the importer stores it) is named with its line where a face uses it
// (data starts on line `first_line`); one no face uses is harmless.
void check_text(std::string_view data, std::uint64_t first_line, const Header& h, const std::string& name) {
  std::size_t at = 0;
  std::uint64_t next = first_line, line = first_line;  // the line at `at`; the instance's
  std::unordered_map<std::uint64_t, std::uint64_t> not_finite;  // vertex -> its line
  std::string_view text, w;
  for (const Element& e : h.elements)
    for (std::uint64_t i = 0; i < e.count; ++i) {
      if (!next_line(data, at, text, next, line)) truncated(name, e, i);
      std::size_t in = 0;
      const auto value = [&] {
        if (next_word(text, in, w)) return;
        const std::string element = "'" + e.name + "' element " + std::to_string(i + 1) + " of " +
                                    std::to_string(e.count);
        // The file's last line: cut short, or a count too large; its line either way.
        if (at >= data.size())
          throw InputError(name + ":" + std::to_string(line) + ": PLY data ends early: " + element +
                           " stops short on the file's last line (fewer values than the header's properties ask "
                           "for: a truncated file, or a list longer than its numbers)");
        throw InputError(name + ":" + std::to_string(line) + ": PLY " + element +
                         ": the line holds fewer values than the header's properties ask for");
      };
      for (const Property& p : e.properties) {
        value();
        if (!p.list) {
          if (e.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z") && !finite_in_float(w))
            not_finite.emplace(i, line);
          continue;
        }
        std::uint64_t n = 0;
        if (w.size() > 19 || w.find_first_not_of("0123456789") != std::string_view::npos)
          throw InputError(name + ":" + std::to_string(line) + ": PLY '" + e.name + "' element " +
                           std::to_string(i + 1) + ": list length '" + std::string(w.substr(0, 20)) + "' is not a count");
        for (char c : w) n = n * 10 + unsigned(c - '0');
        if (!fits_type(static_cast<std::int64_t>(n), p.count))
          bad_count(name, e, i, "list length " + std::string(w) + " does not fit its count type");
        const bool corners = !not_finite.empty() && e.name == "face" &&
                             (p.name == "vertex_indices" || p.name == "vertex_index");
        for (std::uint64_t k = 0; k < n; ++k) {
          value();
          if (!corners || w.size() > 19 || w.find_first_not_of("0123456789") != std::string_view::npos) continue;
          const auto bad = not_finite.find(std::stoull(std::string(w)));
          if (bad != not_finite.end())
            throw InputError(name + ":" + std::to_string(line) + ": PLY 'face' element " + std::to_string(i + 1) +
                             " of " + std::to_string(e.count) + ": vertex " + std::string(w) + " (line " +
                             std::to_string(bad->second) + ") is not a finite number");
        }
      }
    }
  const std::size_t rest = data.find_first_not_of(" \t\r\n", std::min(at, data.size()));
  if (rest != std::string_view::npos && every_count_read(h))
    data_past_elements(name, h.elements.back(), true,
                       next + std::uint64_t(std::count(data.begin() + std::ptrdiff_t(std::min(at, data.size())),
                                                       data.begin() + std::ptrdiff_t(rest), '\n')));
}

// The binary data: fixed sizes, lists read for their counts.
void check_binary(std::string_view data, const Header& h, const std::string& name) {
  std::uint64_t at = 0;
  const std::uint64_t size = data.size();
  const bool big_endian = h.format == Format::big_endian;
  for (const Element& e : h.elements) {
    bool lists = false;
    std::uint64_t fixed = 0;
    for (const Property& p : e.properties) lists = lists || p.list, fixed += std::uint64_t(type_bytes(p.type));
    if (!lists) {  // count <= file size (the header's reading), so no overflow
      if (fixed > 0 && e.count > (size - at) / fixed) truncated(name, e, (size - at) / fixed);
      at += e.count * fixed;
      continue;
    }
    for (std::uint64_t i = 0; i < e.count; ++i)
      for (const Property& p : e.properties) {
        std::uint64_t n = 1;
        if (p.list) {
          const int count_bytes = type_bytes(p.count);
          if (std::uint64_t(count_bytes) > size - at) truncated(name, e, i);
          n = 0;
          for (int b = 0; b < count_bytes; ++b) {
            const int k = big_endian ? b : count_bytes - 1 - b;
            n = n << 8 | static_cast<unsigned char>(data[at + std::uint64_t(k)]);
          }
          at += std::uint64_t(count_bytes);
          if (!fits_type(static_cast<std::int64_t>(n), p.count))  // a signed count's sign bit
            bad_count(name, e, i, "list length " + std::to_string(std::int64_t(n) - (std::int64_t(1) << (8 * count_bytes))) +
                                      " is negative");
        }
        const int item_bytes = type_bytes(p.type);
        if (n > (size - at) / std::uint64_t(std::max(1, item_bytes))) truncated(name, e, i);
        at += n * std::uint64_t(item_bytes);
      }
  }
  if (at < size && every_count_read(h)) data_past_elements(name, h.elements.back(), false, h.body + at);
}

}  // namespace

void data_past_elements(const std::string& name, const Element& last, bool text, std::uint64_t where) {
  const std::string what = "data goes on past the " + std::to_string(last.count) + " '" + last.name +
                           "' element(s) the header counts, the last it declares";
  if (text) throw InputError(name + ":" + std::to_string(where) + ": PLY " + what);
  throw InputError(name + ": PLY " + what + " (from byte " + std::to_string(where) + ")");
}

// The importer's PLY reader does not stop on a header that never ends (found
// by fuzz_model), allocates what the element counts ask for before reading
// one, and renders a file that holds fewer elements than its header counts.
void check_ply(const std::string& bytes, const std::string& name) {
  const Header h = parse_header(bytes, bytes.size(), name, Reading::importer);
  // Strips are opsila's PLY reader's (ply_reader.h), which reaches this
  // check only with a header it cannot read: the importer keeps one
  // triangle of them, and a 600-byte file of strips had it ask for 12 GB
  // (found by fuzz_model).
  if (has_strips(h)) {
    std::string why = "its header";
    try {
      parse_header(bytes, bytes.size(), name, Reading::stream);
    } catch (const InputError& e) {
      why = e.what();
    }
    throw InputError(name + ": PLY triangle strips are read only by opsila's PLY reader, which cannot read this "
                            "file (" + why + ")");
  }
  const std::string_view body = std::string_view(bytes).substr(h.body);
  if (h.format == Format::ascii) check_text(body, 1 + std::uint64_t(h.lines), h, name);
  else check_binary(body, h, name);
  // The importer reads a position without z as one at z = 0 (the stream
  // leaves such a file to it).
  for (const Element& e : h.elements) {
    if (e.name != "vertex") continue;
    for (const char* axis : {"x", "y", "z"})
      if (std::none_of(e.properties.begin(), e.properties.end(), [&](const Property& p) { return p.name == axis; }))
        throw InputError(name + ": PLY 'vertex' element: no '" + axis + "' property (a position is x, y and z)");
  }
  // Points only: the importer's validation would refuse its empty mesh
  // ("Mesh contains no faces"). Its readers take faces from these elements.
  bool faces = false;
  for (const Element& e : h.elements) {
    const std::string n = lower(e.name);
    faces = faces || (e.count > 0 && (n.rfind("face", 0) == 0 || n.rfind("tristrips", 0) == 0 ||
                                      n.rfind("range_grid", 0) == 0));
  }
  if (!faces)
    throw InputError(name + ": no facets (the PLY file has no faces: no 'face' element with entries, points only)");
}

}  // namespace ply
}  // namespace opsila
