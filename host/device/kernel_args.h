// One typed, checked way to bind a kernel's arguments. A KernelBinding's
// type lists the kernel's parameters as the host passes them, once: its
// constructor compares their number with CL_KERNEL_NUM_ARGS as soon as the
// program is built (a kernel whose signature changed fails there, naming
// it, not as a wrong pixel), and bind() sets them all in order, each call
// checked. A value that stands for several parameters (a descriptor vector
// and its destination stream, the surface buffers) says so with
// kernel_args(), a tuple of its parts. Nowhere else does the host call
// clSetKernelArg.
#pragma once

#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "device/cl_runtime.h"

namespace opsila {

namespace kernel_args_detail {

template <typename T, typename = void>
struct Parts : std::false_type {};
template <typename T>
struct Parts<T, std::void_t<decltype(std::declval<const T&>().kernel_args())>> : std::true_type {};

template <typename T>
constexpr int count() {
  if constexpr (Parts<T>::value)
    return static_cast<int>(std::tuple_size_v<decltype(std::declval<const T&>().kernel_args())>);
  else
    return 1;
}

void check_set(cl_int err, const std::string& kernel, int index);

template <typename T>
void set(cl::Kernel& k, const std::string& kernel, int& at, const T& value) {
  if constexpr (Parts<T>::value) {
    std::apply([&](const auto&... part) { (set(k, kernel, at, part), ...); }, value.kernel_args());
  } else {
    check_set(k.setArg(static_cast<cl_uint>(at), value), kernel, at);
    ++at;
  }
}

// Throws ClError unless `k` takes `expected` arguments.
void check_arity(const cl::Kernel& k, const std::string& kernel, int expected);

}  // namespace kernel_args_detail

template <typename... Args>
class KernelBinding {
 public:
  static constexpr int kArgs = (kernel_args_detail::count<Args>() + ... + 0);

  KernelBinding() = default;
  KernelBinding(ClRuntime& rt, const char* name, KernelProgram program = KernelProgram::render)
      : kernel_(rt.kernel(name, program)), name_(name) {
    kernel_args_detail::check_arity(kernel_, name_, kArgs);
  }
  // Sets every argument, in the kernel's order.
  cl::Kernel& bind(const Args&... args) {
    int at = 0;
    (kernel_args_detail::set(kernel_, name_, at, args), ...);
    return kernel_;
  }
  cl::Kernel& kernel() { return kernel_; }
  const std::string& name() const { return name_; }

 private:
  cl::Kernel kernel_;
  std::string name_;
};

}  // namespace opsila
