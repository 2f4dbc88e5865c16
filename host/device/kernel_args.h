// One typed, checked way to bind a kernel's arguments, and the rule that
// makes a misplaced buffer a compile error:
//  - every kernel has an argument struct of named fields, and its
//    KernelBinding<Args> takes that struct alone; kernel_args() returns the
//    fields, in the order of the kernel's signature, as a tuple. That
//    order is written once, there; a call site only names fields
//    (`a.pool = pool;`), so no call site can put them out of order;
//  - each buffer in such a struct is a DeviceArray of its own role (below),
//    so a buffer given where another is expected (the descriptors where
//    the bank's facets go, two counters swapped) does not compile;
//  - parts that always travel together (a bank's nodes and facets, a
//    descriptor vector and its sort keys, the surface buffers) are one
//    struct with kernel_args() of their own, nested as they are: a value
//    with kernel_args() stands for its parts, at any depth.
// The binding's constructor compares the number of parts with
// CL_KERNEL_NUM_ARGS as soon as the program is built (a kernel whose
// signature changed fails there, naming it, not as a wrong pixel), and
// bind() sets them all in order, each call checked. Nowhere else does the
// host call clSetKernelArg.
#pragma once

#include <cstddef>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "device/cl_runtime.h"

namespace opsila {

// A device buffer in one role: `using BankFacets = DeviceArray<struct
// BankFacetsRole>;` declares a role, once, beside the code that owns the
// buffer. The role is only a tag; one kernel argument.
template <class Role>
struct DeviceArray {
  cl::Buffer buffer;
  DeviceArray() = default;
  // Explicit, and no aggregate: a handle of another role (which converts to
  // its buffer, below) neither initializes nor is assigned to this one.
  explicit DeviceArray(cl::Buffer b) : buffer(std::move(b)) {}
  auto kernel_args() const { return std::tie(buffer); }
  // Copies, reads and maps take it as the plain buffer it is.
  operator const cl::Buffer&() const { return buffer; }
};

namespace kernel_args_detail {

template <typename T, typename = void>
struct Parts : std::false_type {};
template <typename T>
struct Parts<T, std::void_t<decltype(std::declval<const T&>().kernel_args())>> : std::true_type {};

template <typename T>
constexpr int count();

template <typename Tuple, std::size_t... I>
constexpr int count_each(std::index_sequence<I...>) {
  return (count<std::decay_t<std::tuple_element_t<I, Tuple>>>() + ... + 0);
}

// The kernel arguments a value stands for: its parts', or one.
template <typename T>
constexpr int count() {
  if constexpr (Parts<T>::value) {
    using Tuple = decltype(std::declval<const T&>().kernel_args());
    return count_each<Tuple>(std::make_index_sequence<std::tuple_size_v<Tuple>>{});
  } else {
    return 1;
  }
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
