// Bounded, checked reading of the files a run reads (scenes, models,
// images, OPSILA_KERNEL_SOURCE, a saved bench): regular files only, never
// more than a given size, a chunk at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace opsila {

// Upper bound on the size of any input file read by the loaders.
constexpr std::size_t kMaxInputFileBytes = std::size_t(1) << 31;

// Called on each chunk of a file as it is read (bytes, count, offset of the
// first byte); throws InputError to refuse the file there.
using ChunkCheck = std::function<void(const char*, std::size_t, std::size_t)>;

// Reads a regular file of at most max_bytes a chunk at a time: `sized`
// hears its size once it is open, and each chunk is checked, then taken,
// before the next is read.
using ChunkTake = std::function<void(const char*, std::size_t)>;
void read_file_chunks(const std::string& path, std::size_t max_bytes, const ChunkCheck& check,
                      const std::function<void(std::uintmax_t)>& sized, const ChunkTake& take);
// Reads a whole regular file of at most max_bytes, a chunk at a time, each
// chunk checked before the next is read. Directories, devices, unreadable or
// oversized files give an InputError naming the path.
std::string read_input_file(const std::string& path, std::size_t max_bytes,
                            const ChunkCheck& check = {});
// Any file (an image) of at most kMaxInputFileBytes.
std::string read_input_file(const std::string& path);
// A text file (OBJ, MTL) of at most kMaxInputFileBytes: a NUL byte (a binary
// file) is refused as soon as it is read, not after gigabytes.
std::string read_text_file(const std::string& path);
// That check, for a file read in chunks: UTF-16 and NUL bytes, by line.
ChunkCheck text_check(const std::string& path);
// The same for a file named by `origin` (an environment variable or a
// flag): every message starts "ORIGIN=PATH: " ("--compare PATH: ").
std::string read_named_file(const std::string& origin, const std::string& path, std::size_t max_bytes);

// What a rank read of a file it streams, for the ranks to compare before
// they exchange anything (SceneShare::reads): the file's size and
// modification time before the first read and after the last, then the
// reader's own figures of what it read (fan triangles, triangles, facets).
// Throws InputError naming the file when it changed during this rank's reads.
struct FileReadStamp {
  explicit FileReadStamp(const std::string& path);  // before the first read
  std::vector<std::uint64_t> after(std::uint64_t fans, std::uint64_t triangles, std::uint64_t facets) const;

 private:
  std::string path_;
  std::vector<std::uint64_t> before_;
};

}  // namespace opsila
