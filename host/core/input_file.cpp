#include "core/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>
#include <vector>

#include "core/errors.h"
#include "core/stage_clock.h"

namespace opsila {

namespace {

// The descriptor of an input, checked on itself (so the file checked is the
// file read: a path swapped for a FIFO after a check on the name would block
// the open for ever). O_NONBLOCK keeps a FIFO from blocking the open; it is
// refused as not a regular file, and a regular file is then read blocking.
class InputDescriptor {
 public:
  InputDescriptor(const std::string& path, std::uintmax_t& size) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd_ < 0)
      throw InputError(path + ": cannot open: " + (errno == ENOENT ? "no such file" : std::strerror(errno)));
    struct stat st {};
    if (::fstat(fd_, &st) != 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) fail(path, "is a directory, not a file");
    if (!S_ISREG(st.st_mode)) fail(path, "is not a regular file");
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags < 0 || ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK) != 0)
      fail(path, std::string("cannot open: ") + std::strerror(errno));
    size = std::uintmax_t(st.st_size);
  }
  ~InputDescriptor() { ::close(fd_); }
  InputDescriptor(const InputDescriptor&) = delete;
  InputDescriptor& operator=(const InputDescriptor&) = delete;
  // Up to n bytes; 0 at the end; -1 on a read error.
  long read(char* to, std::size_t n) {
    for (;;) {
      const ssize_t got = ::read(fd_, to, n);
      if (got >= 0 || errno != EINTR) return static_cast<long>(got);
    }
  }

 private:
  [[noreturn]] void fail(const std::string& path, const std::string& what) {
    ::close(fd_);
    throw InputError(path + ": " + what);
  }
  int fd_ = -1;
};

}  // namespace

void read_file_chunks(const std::string& path, std::size_t max_bytes, const ChunkCheck& check,
                      const std::function<void(std::uintmax_t)>& sized, const ChunkTake& take) {
  std::uintmax_t size = 0;
  InputDescriptor in(path, size);
  const auto too_large = [&](std::uintmax_t bytes) {
    throw InputError(path + ": file too large (" + std::to_string(bytes) +
                     " bytes; the limit is " + std::to_string(max_bytes) + ")");
  };
  if (size > max_bytes) too_large(size);
  sized(size);
  // Read and checked a chunk at a time: a binary file is refused at its
  // first bad byte, not after gigabytes, and a file that grows while it is
  // read is still held to the limit.
  const std::size_t kChunk = std::size_t(1) << 20;
  std::vector<char> chunk(kChunk);
  StageClock clock(PrepareStage::read);
  for (std::size_t done = 0;;) {
    if (size > 0) clock.progress(double(done) / double(size));
    std::size_t got = 0;  // a whole chunk unless the file ends: checks see the same chunks as before
    while (got < chunk.size()) {
      const long n = in.read(chunk.data() + got, chunk.size() - got);
      if (n < 0) throw InputError(path + ": read error (" + std::strerror(errno) + ")");
      if (n == 0) break;
      got += static_cast<std::size_t>(n);
    }
    if (got == 0) break;
    if (done + got > max_bytes) too_large(done + got);
    if (check) check(chunk.data(), got, done);
    take(chunk.data(), got);
    done += got;
  }
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
