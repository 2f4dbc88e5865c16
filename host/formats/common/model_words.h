// The words of a text model file as the importer's readers take them
// (PLY, OFF, text STL): shared by the checks of those formats, and the
// quoting of a word in a message, shared by every text reader.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace opsila::model_words {

// The next whitespace-separated word of `text` from `at` (false at the end).
bool next_word(std::string_view text, std::size_t& at, std::string_view& out);
// A number word as the importer stores it, in a float: beyond the float
// range it is infinite.
float float_of(std::string_view w);
// Whether that float is finite.
bool finite_in_float(std::string_view w);
// What the importer's number reader (text STL, OFF) starts a number with: an
// optional sign, then a digit, a point and a digit, or 'nan' or 'inf' (any
// case; not finite, caught where a facet uses it).
bool number_start(std::string_view w);
// A word as shown in a message: quoted, shortened, control bytes escaped.
std::string quote(std::string_view w);

}  // namespace opsila::model_words
