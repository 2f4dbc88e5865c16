// Every environment variable opsila reads, in one place. They are hooks
// for tests, CI and experiments, not settings: the command line is the
// interface. A newcomer adding one adds a row here (name, what it does) and
// reads it with env_hook(); README's "Environment" section lists them too.
// (The MPI launchers' own variables are read by launched_by_mpi, mpi/ranks.h.)
// An empty value counts as unset. Each reader checks its value and refuses a
// bad one with InputError naming NAME=value, or ignores it where said.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace opsila {

#define OPSILA_ENV_HOOKS(X)                                                                                        \
  /* host threads for OBJ parsing and bank builds, 1..1024 (else ignored; default every core) */                   \
  X(threads, "OPSILA_THREADS")                                                                                     \
  /* seconds before a progress line first shows (default 2; a bad value is ignored) */                             \
  X(progress_after, "OPSILA_PROGRESS_AFTER")                                                                       \
  /* seconds the model importer may take before the run ends (default 60 s + 1 s per MiB) */                       \
  X(import_timeout, "OPSILA_IMPORT_TIMEOUT")                                                                       \
  /* bytes of memory the model importer may add while it reads (default: 4 GiB or 64 x the file, at most 3/4 of RAM) */ \
  X(import_memory, "OPSILA_IMPORT_MEMORY")                                                                         \
  /* triangles one MPI rank may hold, 1..2^31-1, below its memory's (tests provoke the refusal with it) */        \
  X(rank_triangle_limit, "OPSILA_RANK_TRIANGLE_LIMIT")                                                             \
  /* work-group size the kernels ask for, a power of two 1..1024 (default 64) */                                   \
  X(group_size, "OPSILA_GROUP_SIZE")                                                                               \
  /* a file of OpenCL C built instead of the embedded kernels */                                                   \
  X(kernel_source, "OPSILA_KERNEL_SOURCE")                                                                         \
  /* bytes of device memory to plan with, below what the device reports */                                         \
  X(device_memory_limit, "OPSILA_DEVICE_MEMORY_LIMIT")                                                             \
  /* a device fault injected at this round of every frame (reliability tests) */                                   \
  X(fault_round, "OPSILA_FAULT_ROUND")                                                                             \
  /* descriptors that may wait before the exchange throttles (default: the planned pool x depth) */               \
  X(waiting_limit, "OPSILA_WAITING_LIMIT")                                                                        \
  /* 0: each round's primary descriptors get a launch of their own (default 1: the SPMD launch before builds them) */ \
  X(primary_ahead, "OPSILA_PRIMARY_AHEAD")                                                                          \
  /* 1: every launch keeps its event and time; 0: only the long ones (default: RenderSettings::launch_records) */ \
  X(launch_events, "OPSILA_LAUNCH_EVENTS")                                                                         \
  /* 1: the image resolved on the device where it has doubles; 0: decoded on the host (default: on a GPU) */     \
  X(device_resolve, "OPSILA_DEVICE_RESOLVE")                                                                       \
  /* 1: the bank walks read quantised nodes (half the bytes); 0: float ones (default: quantised on a GPU) */      \
  X(quant_nodes, "OPSILA_QUANT_NODES")

enum class EnvHook {
#define OPSILA_ENV_ENUM(id, name) id,
  OPSILA_ENV_HOOKS(OPSILA_ENV_ENUM)
#undef OPSILA_ENV_ENUM
};

const char* env_hook_name(EnvHook hook);
// The variable's value; nullptr when it is unset or empty.
const char* env_hook(EnvHook hook);
// A whole number in [lo, hi] or nothing when unset; throws InputError
// "NAME=value: expected <expected>" for anything else.
std::optional<std::uint64_t> env_hook_number(EnvHook hook, std::uint64_t lo, std::uint64_t hi,
                                             const char* expected);

// A warning for each OPSILA_* variable set that no part of opsila reads
// (a misspelt hook would otherwise change nothing, without a word), with
// the hook it is nearest to. OPSILA_TEST_DEVICE (the tests') and
// OPSILA_NO_APT (tools/setup.sh's) are known too.
std::vector<std::string> unknown_env_hooks();

// The files the variables name that a run reads (OPSILA_KERNEL_SOURCE):
// inputs, which no output may replace.
std::vector<std::string> env_hook_inputs();

}  // namespace opsila
