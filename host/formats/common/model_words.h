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
// Whether a word is one whole number as the importer's number reader (text
// STL, OFF) reads it: an optional sign, digits with at most one point (a
// digit on either side), an optional exponent, or 'nan', 'inf', 'infinity'
// (any case; not finite, caught where a facet uses it). The reader stops at
// the first character it cannot take and reads the rest as the next number
// or keyword ('0.5.5' as 0.5 and .5), so anything else is refused.
bool whole_number(std::string_view w);
// A word as shown in a message: quoted, shortened, control bytes escaped.
std::string quote(std::string_view w);
// Text of another's (the importer's refusal, which may quote the rest of
// the file after a bad number: megabytes, line breaks, any bytes) as part of
// one message line: line breaks and tabs as spaces, other control and
// non-ASCII bytes escaped, cut after `most` characters with "...".
std::string one_line(std::string_view text, std::size_t most);

}  // namespace opsila::model_words
