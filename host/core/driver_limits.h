// What an OpenCL driver needs of the process and would otherwise abort or
// crash without, said in one clear error before the first OpenCL call.
#pragma once

namespace opsila {

// Before any OpenCL call (listing the devices included):
//   - POCL_CACHE_DIR set but empty: PoCL fails an assertion;
//   - open files (ulimit -n): PoCL's compiler and linker need some 30 with a
//     cold kernel cache. A soft limit below that is raised towards the hard
//     one; a hard limit below it is an error;
//   - threads (ulimit -u): PoCL starts a thread per core when it is loaded
//     and aborts when one cannot start; as many are started (and ended) here
//     first, so that the limit is named instead.
// Throws InputError naming the variable or the limit.
void check_driver_preconditions();

// On a CPU device (PoCL), whose threads run the kernels on the process's
// stack size: a stack limit (ulimit -s) of at least 1 MiB. Throws InputError
// naming the limit.
void check_cpu_driver_environment();

}  // namespace opsila
