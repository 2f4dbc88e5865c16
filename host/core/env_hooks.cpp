#include "core/env_hooks.h"

#include <unistd.h>  // environ

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/errors.h"

namespace opsila {

const char* env_hook_name(EnvHook hook) {
  switch (hook) {
#define OPSILA_ENV_NAME(id, name) \
  case EnvHook::id:               \
    return name;
    OPSILA_ENV_HOOKS(OPSILA_ENV_NAME)
#undef OPSILA_ENV_NAME
  }
  return "";
}

const char* env_hook(EnvHook hook) {
  const char* value = std::getenv(env_hook_name(hook));
  return value && *value ? value : nullptr;
}

std::optional<std::uint64_t> env_hook_number(EnvHook hook, std::uint64_t lo, std::uint64_t hi,
                                             const char* expected) {
  const char* text = env_hook(hook);
  if (!text) return std::nullopt;
  const std::string value = text;
  std::uint64_t n = 0;
  bool ok = value.size() <= 19;
  for (char c : value) {
    ok = ok && c >= '0' && c <= '9';
    if (ok) n = n * 10 + std::uint64_t(c - '0');
  }
  if (!ok || n < lo || n > hi)
    throw InputError(std::string(env_hook_name(hook)) + "=" + value + ": expected " + expected);
  return n;
}

namespace {

// Edits (insert, delete, replace) from a to b: the hook a misspelt name means.
std::size_t edits(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::vector<std::string> unknown_env_hooks() {
  static const char* const kHooks[] = {
#define OPSILA_ENV_LIST(id, name) name,
      OPSILA_ENV_HOOKS(OPSILA_ENV_LIST)
#undef OPSILA_ENV_LIST
      "OPSILA_TEST_DEVICE", "OPSILA_NO_APT"};  // the tests' device, tools/setup.sh's switch
  std::vector<std::string> warnings;
  for (char** e = environ; e && *e; ++e) {
    const char* eq = std::strchr(*e, '=');
    const std::string name(*e, eq ? std::size_t(eq - *e) : std::strlen(*e));
    if (name.compare(0, 7, "OPSILA_") != 0) continue;
    std::string nearest;
    std::size_t best = 4;  // more edits than this: no guess
    for (const char* hook : kHooks) {
      const std::size_t d = edits(name, hook);
      if (d == 0) best = 0;
      if (d < best) best = d, nearest = hook;
    }
    if (best == 0) continue;
    warnings.push_back(name + " is set but opsila reads no such variable" +
                       (nearest.empty() ? "" : " (did you mean " + nearest + "?)") +
                       "; the variables are listed in docs/RELIABILITY.md");
  }
  std::sort(warnings.begin(), warnings.end());
  return warnings;
}

std::vector<std::string> env_hook_inputs() {
  std::vector<std::string> files;
  if (const char* kernels = env_hook(EnvHook::kernel_source)) files.push_back(kernels);
  return files;
}

}  // namespace opsila
