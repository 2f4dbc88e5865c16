// Small utilities every room may use: text case, medians of timings, byte
// counts for people.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace opsila {

// ASCII lower case.
std::string lower(std::string s);

// The folder of a path ("." when it has none) and its last component.
std::string folder_of(const std::string& path);
std::string name_of(const std::string& path);

// The lower median: always one of the values (0 when empty).
double median(std::vector<double> v);
// Index of the value closest to the median (the run whose details are kept).
std::size_t median_index(const std::vector<double>& v);

// Smallest, median and largest of repeated timings (0 when there are none).
struct Spread {
  double min = 0, median = 0, max = 0;
};
Spread spread_of(const std::vector<double>& v);

double seconds_since(std::chrono::steady_clock::time_point t0);

// `text` as a terminal line shows it: control bytes (a carriage return, an
// escape sequence from a file's name) written as \xNN and a line break as
// \n, so that a message stays one line and cannot rewrite the terminal.
std::string shown_text(const std::string& text);
// `text` without the blanks (and NULs) at either end.
std::string trim_blanks(std::string text);

// "12.3 MiB": the largest binary unit (KiB, MiB, GiB) not above `bytes`,
// never below `smallest` (1 = KiB, 2 = MiB), with `decimals` digits.
std::string format_bytes(double bytes, int decimals, int smallest = 1);
// "812 bytes", "35.2 KiB", "12.0 MiB": exact below 10 KiB (for limits in messages).
std::string format_size(std::uint64_t bytes);

// Arrays of a megabyte or more get pages of their own, handed back when
// freed (glibc: a fixed mmap threshold). By default the threshold rises
// after each such free, so that the partition's many per-bank arrays
// (64 banks: a few MB each) stayed in the heap once freed: the peak of an
// 8.4 M-triangle terrain on 64 PEs was 1.5 GB against 1.0 GB with this.
// Called once, first thing, by the program.
void return_large_frees_to_system();

}  // namespace opsila
