// FBX text: the embedded files (a texture's `Content`), base64 in quoted
// strings, are checked before the importer decodes them. Its decoder
// writes past its buffer at any character outside the base64 alphabet (a
// line break or one flipped byte in a texture's text corrupted the heap),
// so such content is refused, naming its line.
#include <cctype>
#include <cstddef>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"

namespace opsila {

namespace {

bool base64_letter(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/';
}

// What is wrong with one quoted piece of base64 (empty: nothing): only the
// alphabet, '=' only as one or two last characters, whole groups of four.
std::string base64_fault(std::string_view s) {
  std::size_t letters = s.size();
  while (letters > 0 && s.size() - letters < 2 && s[letters - 1] == '=') --letters;
  for (std::size_t i = 0; i < letters; ++i)
    if (!base64_letter(s[i])) {
      const unsigned char c = static_cast<unsigned char>(s[i]);
      const std::string shown = c >= 0x20 && c < 0x7f ? "'" + std::string(1, s[i]) + "'" : "byte " + std::to_string(c);
      return "character " + std::to_string(i + 1) + ", " + shown + ", is not base64 (A-Z, a-z, 0-9, +, /, then at most "
             "two '=')";
    }
  if (s.size() % 4 != 0)
    return "its " + std::to_string(s.size()) + " characters are not whole groups of four (truncated or corrupted)";
  return "";
}

}  // namespace

void check_fbx_text(const std::string& bytes, const std::string& name) {
  if (bytes.compare(0, 18, "Kaydara FBX Binary") == 0) return;  // binary: content is raw bytes
  std::size_t line = 1;
  const std::size_t n = bytes.size();
  bool after_content = false;  // inside the value list of a Content key
  for (std::size_t i = 0; i < n; ++i) {
    const char c = bytes[i];
    if (c == '\n') ++line;
    if (c == ';') {  // a comment, to the end of its line
      while (i + 1 < n && bytes[i + 1] != '\n') ++i;
    } else if (c == '"') {
      const std::size_t end = bytes.find('"', i + 1);
      if (end == std::string::npos) return;  // the importer's tokenizer says so
      const std::string_view s(bytes.data() + i + 1, end - i - 1);
      if (after_content) {
        const std::string fault = base64_fault(s);
        if (!fault.empty())
          throw InputError(name + ":" + std::to_string(line) + ": FBX embedded file (Content): " + fault);
      }
      for (char q : s) line += q == '\n';
      i = end;
    } else if (bytes.compare(i, 8, "Content:") == 0 && (i == 0 || !std::isalnum(static_cast<unsigned char>(bytes[i - 1])))) {
      after_content = true;
      i += 7;
    } else if (c != ',' && c != ' ' && c != '\t' && c != '\r' && c != '\n') {
      after_content = false;
    }
  }
}

}  // namespace opsila
