// The one error line of a process that must stop at once: a library's fault
// caught by a signal handler, or a watchdog ending a read that hangs or
// swells (formats/assimp/model_import.cpp). No exception carries it and no
// collective can agree on it, so under MPI each rank would print its own:
// every rank reads the same model and fails alike. Here a rank other than 0
// waits before it writes, long enough for the launcher to have ended the
// job if rank 0 failed too; a rank that fails alone still says so.
#pragma once

#include <cstddef>
#include <string>

namespace opsila {

// Where this process stands in its job, once it has joined one (mpi/).
void set_last_words_rank(int rank, int ranks);

// "rank 2: " in a job of several ranks, "" otherwise: the lines' prefix.
std::string last_words_label();

// Where the read these lines guard was asked for ("s.json:7: objects[5].file: "),
// while one is alive: the lines name it before the file. Scopes nest.
class LastWordsPlace {
 public:
  explicit LastWordsPlace(std::string where);
  ~LastWordsPlace();
  LastWordsPlace(const LastWordsPlace&) = delete;
  LastWordsPlace& operator=(const LastWordsPlace&) = delete;

 private:
  std::string before_;
};

// The label, then the innermost place: what a line puts before the file.
std::string last_words_prefix();

// Writes `text` to `fd` and ends the process with `code`, a rank other than
// 0 first waiting (worked_seconds, the time the failed read had run, or
// 3 s, whichever is longer: rank 0 reads the same bytes). Only
// async-signal-safe calls: a signal handler may call it.
[[noreturn]] void say_last_words(int fd, const char* text, std::size_t length, double worked_seconds, int code);

}  // namespace opsila
