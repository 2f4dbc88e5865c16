// A kernel argument struct (device/kernel_args.h) against the kernel it
// binds, on the test device: its parts number CL_KERNEL_NUM_ARGS, and part
// by part each buffer meets a buffer parameter and each value a parameter
// of its size (where the driver keeps argument information). Shared by the
// tests of the frame's, the exchange's and the baselines' kernels.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "device/cl_runtime.h"
#include "device/kernel_args.h"
#include "opsila_shared.h"

namespace opsila {
const std::string& kernel_source();           // the embedded kernels (generated from kernels/*.cl)
const std::string& baseline_kernel_source();  // and the baselines'
}  // namespace opsila

namespace opsila::test {

// The renderer's and the baselines' programs, built once more with
// -cl-kernel-arg-info so that the driver tells each parameter's kind;
// released with the test runtime (test_device.h).
struct DescribedPrograms {
  cl::Program programs[2];
  bool built[2] = {false, false};
};
inline DescribedPrograms& described_slot() {
  static DescribedPrograms d;
  return d;
}
class DescribedRelease : public ::testing::Environment {
 public:
  void TearDown() override { described_slot() = DescribedPrograms(); }
};
inline ::testing::Environment* const kDescribedRelease = ::testing::AddGlobalTestEnvironment(new DescribedRelease);

inline cl::Program& described_program(ClRuntime& rt, bool baselines) {
  DescribedPrograms& d = described_slot();
  const int i = baselines ? 1 : 0;
  if (!d.built[i]) {
    d.programs[i] = cl::Program(rt.context(), baselines ? baseline_kernel_source() : kernel_source());
    cl_check(d.programs[i].build({rt.device().device}, "-cl-std=CL1.2 -cl-kernel-arg-info"),
             "clBuildProgram(-cl-kernel-arg-info)");
    d.built[i] = true;
  }
  return d.programs[i];
}

// One kernel argument: "buffer", or a value's size in bytes.
template <class T>
void host_parts(std::vector<std::string>& out);

template <class Tuple, std::size_t... I>
void host_parts_each(std::vector<std::string>& out, std::index_sequence<I...>) {
  (host_parts<std::decay_t<std::tuple_element_t<I, Tuple>>>(out), ...);
}

template <class T>
void host_parts(std::vector<std::string>& out) {
  if constexpr (kernel_args_detail::Parts<T>::value) {
    using Tuple = decltype(std::declval<const T&>().kernel_args());
    host_parts_each<Tuple>(out, std::make_index_sequence<std::tuple_size_v<Tuple>>{});
  } else if constexpr (std::is_same_v<T, cl::Buffer>) {
    out.push_back("buffer");
  } else {
    out.push_back(std::to_string(sizeof(T)) + " bytes");
  }
}

// The kernel's parameters in the same terms, with their names; empty when
// the driver keeps no argument information even so.
inline std::vector<std::pair<std::string, std::string>> kernel_parts(const cl::Kernel& k, cl_uint n) {
  // The value types the kernels take, by the name the driver reports.
  const std::pair<const char*, std::size_t> sizes[] = {
      {"int", sizeof(cl_int)},     {"uint", sizeof(cl_uint)},     {"float", sizeof(cl_float)},
      {"int2", sizeof(cl_int2)},   {"int4", sizeof(cl_int4)},     {"float4", sizeof(cl_float4)},
      {"FrameParams", sizeof(FrameParams)}};
  std::vector<std::pair<std::string, std::string>> parts;
  for (cl_uint i = 0; i < n; ++i) {
    cl_kernel_arg_address_qualifier where = 0;
    if (k.getArgInfo(i, CL_KERNEL_ARG_ADDRESS_QUALIFIER, &where) != CL_SUCCESS) return {};
    std::string name, type;
    k.getArgInfo(i, CL_KERNEL_ARG_NAME, &name);
    k.getArgInfo(i, CL_KERNEL_ARG_TYPE_NAME, &type);
    name = name.c_str(), type = type.c_str();  // without the terminating zero
    std::string part = "value of type " + type;
    if (where == CL_KERNEL_ARG_ADDRESS_GLOBAL || where == CL_KERNEL_ARG_ADDRESS_CONSTANT) part = "buffer";
    for (const auto& [t, bytes] : sizes)
      if (where == CL_KERNEL_ARG_ADDRESS_PRIVATE && type == t) part = std::to_string(bytes) + " bytes";
    parts.emplace_back(part, name);
  }
  return parts;
}

template <class Args>
void expect_follows_signature(ClRuntime& rt, const char* kernel, KernelProgram program) {
  SCOPED_TRACE(kernel);
  cl::Kernel k = rt.kernel(kernel, program);
  cl_uint n = 0;
  ASSERT_EQ(k.getInfo(CL_KERNEL_NUM_ARGS, &n), CL_SUCCESS);
  ASSERT_EQ(KernelBinding<Args>::kArgs, static_cast<int>(n));
  std::vector<std::string> host;
  host_parts<Args>(host);
  ASSERT_EQ(host.size(), std::size_t(n));
  const bool baselines = program == KernelProgram::baselines || program == KernelProgram::baselines_uncounted;
  const auto declared = kernel_parts(cl::Kernel(described_program(rt, baselines), kernel), n);
  for (std::size_t i = 0; i < declared.size(); ++i)
    EXPECT_EQ(host[i], declared[i].first) << "argument " << i << " (" << declared[i].second << ")";
}

// Several structs, each against the kernel named in the same place of
// `kernels`, in `program`.
template <class... Args>
void expect_follow_signatures(ClRuntime& rt, KernelProgram program,
                              const std::array<const char*, sizeof...(Args)>& kernels) {
  std::size_t i = 0;
  (expect_follows_signature<Args>(rt, kernels[i++], program), ...);
}

}  // namespace opsila::test
