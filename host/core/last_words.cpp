#include "core/last_words.h"

#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <mutex>
#include <utility>

namespace opsila {

namespace {
// Set once, before any read that these lines guard; read by signal handlers.
volatile int g_rank = 0;
volatile int g_ranks = 1;
std::mutex g_place_mutex;
std::string g_place;  // the innermost LastWordsPlace's
}  // namespace

LastWordsPlace::LastWordsPlace(std::string where) {
  std::lock_guard<std::mutex> lock(g_place_mutex);
  before_ = std::move(g_place);
  g_place = std::move(where);
}

LastWordsPlace::~LastWordsPlace() {
  std::lock_guard<std::mutex> lock(g_place_mutex);
  g_place = std::move(before_);
}

std::string last_words_prefix() {
  std::lock_guard<std::mutex> lock(g_place_mutex);
  return last_words_label() + g_place;
}

void set_last_words_rank(int rank, int ranks) {
  g_rank = rank;
  g_ranks = ranks;
}

std::string last_words_label() { return g_ranks > 1 ? "rank " + std::to_string(g_rank) + ": " : std::string(); }

void say_last_words(int fd, const char* text, std::size_t length, double worked_seconds, int code) {
  if (g_ranks > 1 && g_rank != 0) {
    const double wait = worked_seconds > 3.0 ? (worked_seconds < 600.0 ? worked_seconds : 600.0) : 3.0;
    timespec left{static_cast<time_t>(wait), static_cast<long>((wait - static_cast<double>(time_t(wait))) * 1e9)};
    while (nanosleep(&left, &left) != 0 && errno == EINTR) {
    }
  }
  while (length > 0) {
    const ssize_t n = write(fd, text, length);
    if (n <= 0) break;
    text += n, length -= std::size_t(n);
  }
  _exit(code);
}

}  // namespace opsila
