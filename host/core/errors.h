// The errors a run ends with, by whose fault: bad input here (exit 2); a
// failed OpenCL call or driver fault is ClError (device/cl_runtime.h, exit
// 3); the exit codes themselves are in app/args.h.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace opsila {

// Any bad input (file, flag, scene value, OPSILA_* variable). what() is the
// one-line message the user sees: it names the file, the line (and key) and
// the problem. `warnings` are those the reader had gathered before the
// error: printed before it, so that a misspelt key still shows up.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
  std::vector<std::string> warnings;
};

// A reader that counts triangles as it goes passed the limit it was given:
// the caller, which knows why the limit is what it is (scene/
// triangle_limit.h), adds that to the message.
struct TooManyTriangles : InputError {
  using InputError::InputError;
};

}  // namespace opsila
