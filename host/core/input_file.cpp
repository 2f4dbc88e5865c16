#include "core/input_file.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include "core/errors.h"
#include "core/stage_clock.h"

namespace opsila {

namespace fs = std::filesystem;

void read_file_chunks(const std::string& path, std::size_t max_bytes, const ChunkCheck& check,
                      const std::function<void(std::uintmax_t)>& sized, const ChunkTake& take) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    const std::string why = ec ? ec.message() : "no such file";
    throw InputError(path + ": cannot open: " + why);
  }
  if (fs::is_directory(st)) throw InputError(path + ": is a directory, not a file");
  if (!fs::is_regular_file(st)) throw InputError(path + ": is not a regular file");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read: " + ec.message());
  const auto too_large = [&](std::uintmax_t bytes) {
    throw InputError(path + ": file too large (" + std::to_string(bytes) +
                     " bytes; the limit is " + std::to_string(max_bytes) + ")");
  };
  if (size > max_bytes) too_large(size);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  sized(size);
  // Read and checked a chunk at a time: a binary file is refused at its
  // first bad byte, not after gigabytes, and a file that grows while it is
  // read is still held to the limit.
  const std::size_t kChunk = std::size_t(1) << 20;
  std::vector<char> chunk(kChunk);
  StageClock clock(PrepareStage::read);
  for (std::size_t done = 0;;) {
    if (size > 0) clock.progress(double(done) / double(size));
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const std::size_t got = static_cast<std::size_t>(in.gcount());
    if (got == 0) break;
    if (done + got > max_bytes) too_large(done + got);
    if (check) check(chunk.data(), got, done);
    take(chunk.data(), got);
    done += got;
  }
  if (in.bad()) throw InputError(path + ": read error");
}

std::string read_input_file(const std::string& path, std::size_t max_bytes,
                            const ChunkCheck& check) {
  std::string text;
  const auto reserve = [&](std::uintmax_t size) {
    try {
      text.reserve(static_cast<std::size_t>(size));
    } catch (const std::bad_alloc&) {
      throw InputError(path + ": out of memory reading the file");
    }
  };
  read_file_chunks(path, max_bytes, check, reserve, [&](const char* data, std::size_t n) { text.append(data, n); });
  return text;
}

std::string read_named_file(const std::string& origin, const std::string& path, std::size_t max_bytes) {
  try {
    return read_input_file(path, max_bytes);
  } catch (const InputError& e) {
    throw InputError(origin + e.what());
  }
}

namespace {

// Size and modification time (ns); zeros for a file stat cannot see (the
// reader has said why already).
std::vector<std::uint64_t> stamp(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {0, 0};
  const std::uint64_t ns = std::uint64_t(st.st_mtim.tv_sec) * 1000000000u + std::uint64_t(st.st_mtim.tv_nsec);
  return {std::uint64_t(st.st_size), ns};
}

}  // namespace

FileReadStamp::FileReadStamp(const std::string& path) : path_(path), before_(stamp(path)) {}

std::vector<std::uint64_t> FileReadStamp::after(std::uint64_t fans, std::uint64_t triangles,
                                                std::uint64_t facets) const {
  if (stamp(path_) != before_)
    throw InputError(path_ + ": the file changed while it was read (its size or modification time); read it again "
                             "once nothing writes it");
  std::vector<std::uint64_t> figures = before_;
  figures.insert(figures.end(), {fans, triangles, facets});
  return figures;
}

std::string read_input_file(const std::string& path) {
  return read_input_file(path, kMaxInputFileBytes, [](const char*, std::size_t, std::size_t) {});
}

ChunkCheck text_check(const std::string& path) {
  return [path, line = 1](const char* data, std::size_t n, std::size_t at) mutable {
    if (at == 0 && n >= 2 && ((data[0] == '\xff' && data[1] == '\xfe') || (data[0] == '\xfe' && data[1] == '\xff')))
      throw InputError(path + ":1: UTF-16 text is not supported (save the file as UTF-8 or ASCII)");
    // Counted, not looped over byte by byte: this runs at memory speed.
    if (const char* nul = static_cast<const char*>(std::memchr(data, 0, n))) {
      line += static_cast<int>(std::count(data, nul, '\n'));
      throw InputError(path + ":" + std::to_string(line) + ": NUL byte (binary file?)");
    }
    line += static_cast<int>(std::count(data, data + n, '\n'));
  };
}

std::string read_text_file(const std::string& path) { return read_input_file(path, kMaxInputFileBytes, text_check(path)); }

}  // namespace opsila
