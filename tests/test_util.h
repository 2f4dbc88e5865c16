// Helpers shared by the tests: image and item-buffer comparison, temporary
// folders, running the opsila binary and capturing what it says, one-line
// input errors.
#pragma once

#include <dirent.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "formats/image/image_io.h"
#include "scene/scene.h"

extern char** environ;

namespace opsila::test {

// A float's exact value as text (C99 hex), for comparing results as text.
inline std::string hex(float f) {
  char text[32];
  std::snprintf(text, sizeof text, "%a", double(f));
  return text;
}

// PSNR of two linear RGB buffers (values clamped to [0,1] first, peak 1).
inline double clamped_psnr(const std::vector<float>& a, const std::vector<float>& b) {
  auto clamp = [](std::vector<float> v) {
    for (float& x : v) x = std::min(1.0f, std::max(0.0f, std::isnan(x) ? 0.0f : x));
    return v;
  };
  return psnr(clamp(a), clamp(b), 1.0);
}

// Fraction of pixels where some channel differs by more than k/255 after the
// PNG's sRGB 8-bit conversion.
inline double fraction_off(const std::vector<float>& a, const std::vector<float>& b, int k) {
  if (a.size() != b.size() || a.size() % 3 != 0) throw std::invalid_argument("fraction_off: size mismatch");
  if (a.empty()) return 0.0;
  std::size_t off = 0;
  for (std::size_t p = 0; p < a.size(); p += 3) {
    for (int c = 0; c < 3; ++c) {
      if (std::abs(int(to_srgb8(a[p + c])) - int(to_srgb8(b[p + c]))) > k) {
        ++off;
        break;
      }
    }
  }
  return double(off) / double(a.size() / 3);
}

// A fresh folder under $TMPDIR (or /tmp), removed with its contents.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/opsila-test-XXXXXX";
    std::vector<char> buffer(pattern.begin(), pattern.end());
    buffer.push_back('\0');
    if (!::mkdtemp(buffer.data())) throw std::runtime_error("mkdtemp failed");
    path_ = buffer.data();
  }
  ~TempDir() { remove_tree(path_); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string p = file(name);
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  // Names in the folder (hidden ones included), sorted.
  std::vector<std::string> entries() const { return list(path_); }

  static std::vector<std::string> list(const std::string& folder) {
    std::vector<std::string> names;
    if (DIR* dir = ::opendir(folder.c_str())) {
      while (dirent* e = ::readdir(dir)) {
        const std::string name = e->d_name;
        if (name != "." && name != "..") names.push_back(name);
      }
      ::closedir(dir);
    }
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  static void remove_tree(const std::string& p) {
    struct stat st;
    if (::lstat(p.c_str(), &st) != 0) return;
    if (S_ISDIR(st.st_mode)) {
      for (const std::string& name : list(p)) remove_tree(p + "/" + name);
      ::rmdir(p.c_str());
    } else {
      ::unlink(p.c_str());
    }
  }
  std::string path_;
};

// An uncompressed 24-bit TGA (top-left origin) with the given sRGB codes.
inline std::string tga(int w, int h, const std::vector<std::array<int, 3>>& rgb) {
  std::string out(18, '\0');
  out[2] = 2;  // uncompressed true-colour
  out[12] = static_cast<char>(w & 255), out[13] = static_cast<char>(w >> 8);
  out[14] = static_cast<char>(h & 255), out[15] = static_cast<char>(h >> 8);
  out[16] = 24;
  out[17] = 0x20;  // rows from the top
  for (const auto& c : rgb) {
    out += static_cast<char>(c[2]);
    out += static_cast<char>(c[1]);
    out += static_cast<char>(c[0]);
  }
  return out;
}

inline bool file_exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

// Occurrences of `needle` in `text` (not overlapping).
inline std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct RunResult {
  int exit_code = -1;  // 128 + signal when killed by one
  long max_rss_kb = 0;  // the program's peak resident memory
  std::string out, err;
  // Lines of stderr that contain "error:".
  std::vector<std::string> error_lines() const {
    std::vector<std::string> lines;
    std::istringstream s(err);
    std::string line;
    while (std::getline(s, line))
      if (line.find("error:") != std::string::npos) lines.push_back(line);
    return lines;
  }
};

// Changes to the environment of a run: a value sets the variable,
// std::nullopt removes it; the rest of this process's environment is kept.
using EnvChanges = std::map<std::string, std::optional<std::string>>;

// Runs `program args...` (no shell), stdout and stderr captured via files
// (stdout into `stdout_to` instead, when given).
inline RunResult run_program(const std::string& program, const std::vector<std::string>& args,
                             const EnvChanges& env = {}, const std::string& stdout_to = "") {
  std::vector<std::string> entries;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    if (!env.count(entry.substr(0, entry.find('=')))) entries.push_back(entry);
  }
  for (const auto& [name, value] : env)
    if (value) entries.push_back(name + "=" + *value);
  std::vector<char*> envp;
  for (std::string& e : entries) envp.push_back(e.data());
  envp.push_back(nullptr);

  TempDir capture;
  const std::string out_path = capture.file("stdout"), err_path = capture.file("stderr");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, stdout_to.empty() ? out_path.c_str() : stdout_to.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(program.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid;
  RunResult result;
  const int spawned = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    result.err = "spawn failed";
    return result;
  }
  int status = 0;
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0) {
  }
  result.max_rss_kb = usage.ru_maxrss;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  return result;
}

// Fraction of pixels whose (object, facet) agree; 0 when the sizes differ.
inline double item_agreement(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
  EXPECT_EQ(a.size(), b.size());
  if (a.size() != b.size() || a.empty()) return 0;
  std::size_t same = 0;
  for (std::size_t i = 0; i + 1 < a.size(); i += 2) same += (a[i] == b[i] && a[i + 1] == b[i + 1]);
  return double(same) / double(a.size() / 2);
}

// The message of the `Error` that `f` throws, or "<no error>".
template <class Error = InputError>
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "<no error>";
}

// The message must name every fragment (file, line, key word) and be one line.
inline void expect_error(const std::function<void()>& f, const std::vector<std::string>& fragments) {
  const std::string msg = error_of(f);
  for (const std::string& frag : fragments)
    EXPECT_NE(msg.find(frag), std::string::npos) << "message \"" << msg << "\" lacks \"" << frag << "\"";
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

#ifdef OPSILA_BINARY
inline RunResult run_opsila(const std::vector<std::string>& args) { return run_program(OPSILA_BINARY, args); }
#endif

}  // namespace opsila::test
