#include "formats/common/model_files.h"

#include <fcntl.h>
#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "core/util.h"
#include "core/input_file.h"
#include "scene/scene.h"

#ifdef OPSILA_HAVE_ASSIMP
#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#endif

namespace opsila {

namespace {

// Opens a file for reading after the checks every input gets, made on the
// open descriptor (so the file checked is the file read). O_NONBLOCK keeps
// a FIFO from blocking the open; it is refused as not a regular file.
std::FILE* open_checked(const std::string& path, std::uint64_t& bytes) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  std::string problem;
  if (::fstat(fd, &st) != 0) problem = std::string("cannot open: ") + std::strerror(errno);
  else if (S_ISDIR(st.st_mode)) problem = "is a directory, not a file";
  else if (!S_ISREG(st.st_mode)) problem = "is not a regular file";
  else if (std::uint64_t(st.st_size) > kMaxInputFileBytes)
    problem = "file too large (the limit is " + std::to_string(kMaxInputFileBytes) + " bytes)";
  const int flags = problem.empty() ? ::fcntl(fd, F_GETFL) : -1;
  std::FILE* f = flags >= 0 && ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) == 0 ? ::fdopen(fd, "rb") : nullptr;
  if (!f) {
    ::close(fd);
    throw InputError(path + ": " + (problem.empty() ? std::string("cannot open: ") + std::strerror(errno) : problem));
  }
  bytes = std::uint64_t(st.st_size);
  return f;
}

}  // namespace

ModelFiles::ModelFiles(std::string main_name, std::string main, std::string other)
    : memory_(true), main_name_(std::move(main_name)), main_(std::move(main)), other_(std::move(other)) {}

void ModelFiles::substitute(const std::string& path, std::string bytes) {
  substitute_name_ = path;
  substitute_ = std::move(bytes);
}

void ModelFiles::record(const std::string& path) {
  if (std::find(files_.begin(), files_.end(), path) == files_.end()) files_.push_back(path);
}

const std::string* ModelFiles::in_memory(const std::string& path) const {
  if (path == main_name_) return &main_;
  return other_.empty() ? nullptr : &other_;
}

std::uint64_t ModelFiles::size(const std::string& path) {
  record(path);
  if (memory_) {
    const std::string* bytes = in_memory(path);
    if (!bytes) throw InputError(path + ": cannot open: no such file");
    return bytes->size();
  }
  std::uint64_t bytes = 0;
  std::fclose(open_checked(path, bytes));
  return bytes;
}

bool ModelFiles::exists(const std::string& path) const {
  if (memory_) return in_memory(path) != nullptr;
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

std::string ModelFiles::head(const std::string& path, std::size_t max_bytes) {
  record(path);
  if (memory_) {
    const std::string* bytes = in_memory(path);
    if (!bytes) throw InputError(path + ": cannot open: no such file");
    return bytes->substr(0, max_bytes);
  }
  std::uint64_t bytes = 0;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(open_checked(path, bytes), &std::fclose);
  std::string out(std::min<std::uint64_t>(bytes, max_bytes), '\0');
  out.resize(std::fread(out.data(), 1, out.size(), f.get()));
  if (std::ferror(f.get())) throw InputError(path + ": cannot read: " + std::strerror(errno));
  return out;
}

#ifdef OPSILA_HAVE_ASSIMP

namespace {

class FileStream : public Assimp::IOStream {
 public:
  FileStream(std::FILE* f, std::uint64_t bytes) : f_(f), bytes_(bytes) {}
  ~FileStream() override { std::fclose(f_); }
  std::size_t Read(void* to, std::size_t size, std::size_t count) override { return std::fread(to, size, count, f_); }
  std::size_t Write(const void*, std::size_t, std::size_t) override { return 0; }  // inputs are never written
  aiReturn Seek(std::size_t offset, aiOrigin origin) override {
    const int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return ::fseeko(f_, static_cast<off_t>(offset), whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
  }
  std::size_t Tell() const override { return static_cast<std::size_t>(::ftello(f_)); }
  std::size_t FileSize() const override { return static_cast<std::size_t>(bytes_); }
  void Flush() override {}

 private:
  std::FILE* f_;
  std::uint64_t bytes_;
};

class MemoryStream : public Assimp::IOStream {
 public:
  explicit MemoryStream(const std::string& bytes) : bytes_(bytes) {}
  std::size_t Read(void* to, std::size_t size, std::size_t count) override {
    if (size == 0) return 0;
    const std::size_t n = std::min(count, (bytes_.size() - at_) / size);
    std::memcpy(to, bytes_.data() + at_, n * size);
    at_ += n * size;
    return n;
  }
  std::size_t Write(const void*, std::size_t, std::size_t) override { return 0; }
  aiReturn Seek(std::size_t offset, aiOrigin origin) override {
    const std::size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? at_ : bytes_.size();
    if (offset > bytes_.size() - base) return aiReturn_FAILURE;
    at_ = base + offset;
    return aiReturn_SUCCESS;
  }
  std::size_t Tell() const override { return at_; }
  std::size_t FileSize() const override { return bytes_.size(); }
  void Flush() override {}

 private:
  const std::string& bytes_;
  std::size_t at_ = 0;
};

}  // namespace

// The importer's window on the file system: records each file before it is
// opened, opens only for reading, and refuses what the checks refuse (the
// importer then fails with its own message; refusal() keeps ours).
class ModelIOSystem : public Assimp::IOSystem {
 public:
  explicit ModelIOSystem(ModelFiles& files) : files_(files) {}
  bool Exists(const char* path) const override { return files_.exists(path); }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* path, const char* mode) override {
    // A still has no motion: the animation and camera files the MD5 reader
    // loads beside a mesh, which nothing checks, are not opened (the reader
    // goes on without them).
    const std::string ext = lower(std::filesystem::path(path).extension().string());
    if (ext == ".md5anim" || ext == ".md5camera") return nullptr;
    files_.record(path);
    if (!mode || mode[0] != 'r') {
      files_.refusal_ = std::string(path) + ": the model importer asked to write it (refused)";
      return nullptr;
    }
    if (!files_.substitute_name_.empty() && path == files_.substitute_name_) return new MemoryStream(files_.substitute_);
    if (files_.memory_) {
      const std::string* bytes = files_.in_memory(path);
      return bytes ? new MemoryStream(*bytes) : nullptr;
    }
    try {
      std::uint64_t bytes = 0;
      std::FILE* f = open_checked(path, bytes);
      return new FileStream(f, bytes);
    } catch (const InputError& e) {
      files_.refusal_ = e.what();
      return nullptr;
    }
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  ModelFiles& files_;
};

Assimp::IOSystem* ModelFiles::io_system() { return new ModelIOSystem(*this); }

#else

Assimp::IOSystem* ModelFiles::io_system() { return nullptr; }

#endif

namespace {

struct StackJob {
  const std::function<void()>* work;
  std::exception_ptr error;
};

void* run_job(void* arg) {
  StackJob& job = *static_cast<StackJob*>(arg);
  try {
    (*job.work)();
  } catch (...) {
    job.error = std::current_exception();
  }
  return nullptr;
}

}  // namespace

void run_with_stack(std::size_t stack_bytes, const std::function<void()>& work) {
  StackJob job{&work, nullptr};
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) != 0) throw std::runtime_error("cannot start the import thread");
  pthread_t thread;
  int rc = pthread_attr_setstacksize(&attr, stack_bytes);
  if (rc == 0) rc = pthread_create(&thread, &attr, &run_job, &job);
  pthread_attr_destroy(&attr);
  if (rc != 0)  // the host's limits (ulimit -v, -u), as running out of memory is: bad input's exit
    throw InputError(std::string("cannot start the model importer's thread with a ") +
                     std::to_string(stack_bytes >> 20) + " MiB stack (" + std::strerror(rc) +
                     "): the process's memory or thread limit (ulimit -v, ulimit -u) is too low");
  pthread_join(thread, nullptr);
  if (job.error) std::rethrow_exception(job.error);
}

}  // namespace opsila
