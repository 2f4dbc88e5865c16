// What the fault and reliability tests share: running the opsila binary
// on a small scene, and the one-error-line rule (docs/RELIABILITY.md).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "device/cl_runtime.h"
#include "test_device.h"
#include "test_util.h"

namespace opsila::test {


// A runtime that ignores OPSILA_* variables of the environment.
inline ClRuntimeOptions plain_options() {
  ClRuntimeOptions o;
  o.read_environment = false;
  return o;
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }


inline RunResult opsila(const std::vector<std::string>& args, const EnvChanges& env = {}) {
  return run_program(OPSILA_BINARY, args, env);
}

// `opsila render` of the small mirror-and-glass OBJ scene into `out`.
inline std::vector<std::string> render_args(const std::string& out, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"render", std::string(OPSILA_SOURCE_DIR) + "/tests/oclgrind/tiny.obj",
                                   "-o",     out,
                                   "--size", "40x30",
                                   "--depth", "5",
                                   "--pes",  "4",
                                   "--light", "2,5,4",
                                   "--light", "-3,4,1,0.4,0.4,0.5",
                                   "--eye",  "1.5,2.2,5",
                                   "--look-at", "0,0.8,0",
                                   "-q"};
  if (*test_device_spec()) args.insert(args.end(), {"--device", test_device_spec()});
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

inline std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// Exactly one "opsila: error: ..." line, naming the problem; whatever follows
// it (a build log) is indented under it. A driver may print its own lines
// before it (PoCL's compiler says "1 error generated.").
inline void expect_one_error(const RunResult& r, int exit_code, const std::string& must_contain) {
  EXPECT_EQ(r.exit_code, exit_code) << r.err;
  std::vector<std::string> lines;
  std::istringstream in(r.err);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::size_t errors = 0, at = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind("opsila: error: ", 0) == 0) ++errors, at = std::min(at, i);
  ASSERT_EQ(errors, 1u) << r.err;
  EXPECT_TRUE(contains(lines[at], must_contain)) << "expected '" << must_contain << "' in: " << lines[at];
  for (std::size_t i = at + 1; i < lines.size(); ++i)
    EXPECT_EQ(lines[i].rfind("    ", 0), 0u) << "unindented line after the error: " << lines[i];
}

// The "opsila: error:" line itself.
inline std::string error_line(const RunResult& r) {
  std::istringstream in(r.err);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("opsila: error: ", 0) == 0) return line;
  return "";
}

}  // namespace opsila::test

// The fault tests' vocabulary, by its short names.
namespace opsila {
using test::contains;
using test::error_line;
using test::expect_one_error;
using test::first_line;
using test::opsila;
using test::plain_options;
using test::render_args;
using test::RunResult;
using test::TempDir;
using test::test_device;
using test::test_device_spec;
}  // namespace opsila
