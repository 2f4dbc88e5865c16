#include "device/kernel_args.h"

namespace opsila {
namespace kernel_args_detail {

void check_set(cl_int err, const std::string& kernel, int index) {
  if (err != CL_SUCCESS)
    cl_check(err, ("clSetKernelArg(" + kernel + ", argument " + std::to_string(index) + ")").c_str());
}

void check_arity(const cl::Kernel& k, const std::string& kernel, int expected) {
  cl_uint n = 0;
  cl_check(k.getInfo(CL_KERNEL_NUM_ARGS, &n), ("clGetKernelInfo(" + kernel + ", CL_KERNEL_NUM_ARGS)").c_str());
  if (static_cast<int>(n) != expected)
    throw ClError("kernel " + kernel + " takes " + std::to_string(n) + " arguments, the host binds " +
                  std::to_string(expected) + " (device/kernel_args.h: its KernelBinding must follow its signature)");
}

}  // namespace kernel_args_detail
}  // namespace opsila
