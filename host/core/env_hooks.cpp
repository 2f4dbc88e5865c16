#include "core/env_hooks.h"

#include <cstdlib>
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

std::vector<std::string> env_hook_inputs() {
  std::vector<std::string> files;
  if (const char* kernels = env_hook(EnvHook::kernel_source)) files.push_back(kernels);
  return files;
}

}  // namespace opsila
