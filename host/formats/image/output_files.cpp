#include "formats/image/output_files.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "formats/image/image_io.h"
#include "scene/scene.h"
#include "core/util.h"

namespace opsila {

namespace fs = std::filesystem;

namespace {

// What the signal handler removes: fixed-size storage written before the
// slot is marked used, so the handler never sees a half-written name.
constexpr int kSlots = 64;
char g_temp[kSlots][PATH_MAX];
volatile sig_atomic_t g_used[kSlots];
char g_folder[PATH_MAX];
volatile sig_atomic_t g_folder_used = 0;

extern "C" void remove_temporaries_and_exit(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_used[i]) ::unlink(g_temp[i]);
  if (g_folder_used) ::rmdir(g_folder);  // only if still empty
  ::_exit(128 + sig);
}

int claim_slot(const std::string& temp) {
  if (temp.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    if (g_used[i]) continue;
    std::memcpy(g_temp[i], temp.c_str(), temp.size() + 1);
    g_used[i] = 1;
    return i;
  }
  return -1;
}

void release_slot(int& slot) {
  if (slot >= 0) g_used[slot] = 0;
  slot = -1;
}

[[noreturn]] void cannot_write(const std::string& path, const std::string& reason) {
  throw InputError(path + ": cannot write (" + reason + ")");
}

// The signals that end a run by default and leave it time to clean up: an
// interrupt, a kill, a closed terminal (SIGHUP), a timer or a CPU limit.
constexpr int kEndingSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGALRM, SIGXCPU};

sigset_t ending_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : kEndingSignals) sigaddset(&set, sig);
  return set;
}

// Signals held back while the outputs are renamed into place.
class HoldSignals {
 public:
  HoldSignals() {
    const sigset_t set = ending_signals();
    pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~HoldSignals() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }

 private:
  sigset_t old_;
};

}  // namespace

void install_interrupt_cleanup() {
  struct sigaction action {};
  action.sa_handler = remove_temporaries_and_exit;
  action.sa_mask = ending_signals();
  for (int sig : kEndingSignals) {
    // A signal the caller ignores stays ignored (nohup's SIGHUP, a
    // background job's SIGINT).
    struct sigaction now {};
    if (::sigaction(sig, nullptr, &now) == 0 && now.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &action, nullptr);
  }
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ea, eb;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ea), ea);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, eb), eb);
  if (ea || eb) return fs::path(a).lexically_normal() == fs::path(b).lexically_normal();
  return ca == cb;
}

OutputFiles::~OutputFiles() { discard(); }

void OutputFiles::declare(const std::string& flag, const std::string& path) {
  const std::string dest = output_destination(path);
  check_output_path(dest);
  for (const Entry& e : entries_)
    if (same_file(e.path, path)) throw InputError(flag + " " + path + ": same file as " + e.flag);
  if (!folder_.empty() && same_file(path, folder_))
    throw InputError(flag + " " + path + ": same as the folder of " + folder_flag_);
  entries_.push_back(Entry{flag, path, "", -1, false, dest});
}

void OutputFiles::declare_folder(const std::string& flag, const std::string& folder,
                                 const std::vector<std::string>& names) {
  struct stat st;
  if (::stat(folder.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw InputError(flag + " " + folder + ": exists and is not a folder");
    for (const std::string& n : names)
      if (::stat((folder + "/" + n).c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw InputError(flag + " " + folder + "/" + n + ": a folder stands where the table goes");
    if (::access(folder.c_str(), W_OK | X_OK) != 0)
      throw InputError(flag + " " + folder + ": cannot write in it (" + std::strerror(errno) + ")");
    if (folder_keeps_its_names(folder))
      throw InputError(flag + " " + folder + ": the folder is append-only or immutable (its files could not be put "
                                             "in place)");
  } else {
    check_output_path(folder);  // its parent exists and is writable
  }
  for (const Entry& e : entries_)
    if (same_file(e.path, folder)) throw InputError(flag + " " + folder + ": same file as " + e.flag);
  folder_flag_ = flag;
  folder_ = folder;
  folder_names_ = names;
}

void OutputFiles::refuse_inputs(const std::vector<std::string>& inputs) {
  for (const std::string& in : inputs) {
    for (const Entry& e : entries_)
      if (same_file(e.path, in))
        throw InputError(e.flag + " " + e.path + ": is an input of this run (" + in +
                         "); choose another output file");
    if (!folder_.empty() && same_file(folder_, in))
      throw InputError(folder_flag_ + " " + folder_ + ": is an input of this run");
    for (const std::string& n : folder_names_)
      if (same_file(folder_ + "/" + n, in))
        throw InputError(folder_flag_ + " " + folder_ + "/" + n + ": is an input of this run (" + in +
                         "); choose another folder");
    inputs_.push_back(in);
  }
}

OutputFiles::Entry& OutputFiles::entry_for(const std::string& path) {
  for (Entry& e : entries_)
    if (e.path == path) return e;
  if (folder_.empty() || folder_of(path) != folder_)
    throw std::logic_error("OutputFiles: " + path + " was not declared");
  for (const std::string& in : inputs_)
    if (same_file(path, in)) {
      discard();
      throw InputError(folder_flag_ + " " + path + ": is an input of this run (" + in + ")");
    }
  entries_.push_back(Entry{folder_flag_, path, "", -1, true, path});
  return entries_.back();
}

void OutputFiles::write(const std::string& path, const std::string& bytes) {
  Entry& e = entry_for(path);
  const auto fail = [&](const std::string& reason) {
    discard();
    cannot_write(path, reason);
  };
  if (e.in_folder && !folder_created_ && ::mkdir(folder_.c_str(), 0777) == 0) {
    folder_created_ = true;
    if (folder_.size() < PATH_MAX) {
      std::memcpy(g_folder, folder_.c_str(), folder_.size() + 1);
      g_folder_used = 1;
    }
  }
  if (!e.temp.empty()) fail("written twice");
  // Next to the destination, so that rename() is atomic; mode 0666 lets the
  // umask decide the final permissions.
  static unsigned counter = 0;
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    // The name cut to 200 bytes: a name of up to 255 (NAME_MAX) stays writable.
    e.temp = folder_of(e.dest) + "/." + name_of(e.dest).substr(0, 200) + ".tmp-" + std::to_string(::getpid()) + "-" +
             std::to_string(counter++);
    e.slot = claim_slot(e.temp);  // before the file exists: a signal may come any time
    if (e.slot < 0) {
      e.temp.clear();
      fail("too many output files");
    }
    fd = ::open(e.temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
      const int err = errno;
      release_slot(e.slot);
      e.temp.clear();
      if (err != EEXIST) fail(std::strerror(err));
    }
  }
  if (fd < 0) fail("no free temporary file name");
  if (const int err = write_all(fd, bytes.data(), bytes.size())) {
    ::close(fd);
    fail(std::strerror(err));
  }
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    const int err = errno;
    ::close(fd);
    fail(std::strerror(err));
  }
  if (::close(fd) != 0) fail(std::strerror(errno));
}

// An output that replaces a file keeps the old one under a second name (a
// hard link beside it) until the whole set is in place: a rename that
// fails after others have succeeded puts the old files back, where it had
// removed them (a table's name held by a folder, a busy mount point).
// Where no link can be made (a file system without them) the old file is
// replaced last among the set, so a failure before it leaves it untouched.
void OutputFiles::commit() {
  HoldSignals hold;
  std::vector<std::string> kept(entries_.size());  // the old file's second name, or ""
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < entries_.size(); ++k) {
    Entry& e = entries_[k];
    if (e.temp.empty()) continue;  // declared, but this run has nothing for it
    struct stat st;
    if (::lstat(e.dest.c_str(), &st) == 0) {
      if (S_ISDIR(st.st_mode)) fail_commit(kept, order, 0, e.path, std::strerror(EISDIR));
      kept[k] = e.temp + ".old";
      if (::link(e.dest.c_str(), kept[k].c_str()) != 0) kept[k].clear();
    }
    order.push_back(k);
  }
  std::stable_partition(order.begin(), order.end(), [&](std::size_t k) {
    return !kept[k].empty() || ::access(entries_[k].dest.c_str(), F_OK) != 0;
  });
  for (std::size_t n = 0; n < order.size(); ++n) {
    Entry& e = entries_[order[n]];
    if (::rename(e.temp.c_str(), e.dest.c_str()) != 0) fail_commit(kept, order, n, e.path, std::strerror(errno));
  }
  for (std::size_t k = 0; k < entries_.size(); ++k) {
    if (!kept[k].empty()) ::unlink(kept[k].c_str());
    entries_[k].temp.clear();
    release_slot(entries_[k].slot);
  }
  g_folder_used = 0;
  folder_created_ = false;
}

// The first `done` of `order` are in place: each goes back to its old file
// (or away, where there was none), then every temporary file.
void OutputFiles::fail_commit(const std::vector<std::string>& kept, const std::vector<std::size_t>& order,
                              std::size_t done, const std::string& path, const std::string& reason) {
  for (std::size_t n = 0; n < done; ++n) {
    Entry& e = entries_[order[n]];
    const std::string& old = kept[order[n]];
    if (old.empty() || ::rename(old.c_str(), e.dest.c_str()) != 0) ::unlink(e.dest.c_str());
    e.temp.clear();
  }
  for (const std::string& old : kept)
    if (!old.empty()) ::unlink(old.c_str());  // those not put back: their files were never replaced
  discard();
  cannot_write(path, reason);
}

void OutputFiles::discard() noexcept {
  for (Entry& e : entries_) {
    if (!e.temp.empty()) ::unlink(e.temp.c_str());
    e.temp.clear();
    release_slot(e.slot);
  }
  if (folder_created_) ::rmdir(folder_.c_str());
  folder_created_ = false;
  g_folder_used = 0;
}

}  // namespace opsila
