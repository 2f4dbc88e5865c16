#!/usr/bin/env bash
# The kernels on a second OpenCL implementation: Mesa's Rusticl with its
# llvmpipe device (Debian's mesa-opencl-icd). Rusticl compiles OpenCL C
# through Mesa's NIR, the path Mesa's GPU drivers take, where PoCL compiles
# through LLVM alone. Runs the test groups that render on the device
# (Renderer, Spp, SurfaceRender, HitOrderRender, Instances, HugeValues, the
# bank walks on both node layouts, and the hit order's and the arithmetic's
# own kernels) there, then checks that a
# gallery scene gives PoCL's PNG, byte for byte.
#
#   .ci/rusticl.sh BUILD_DIR
#
# About 2-3 minutes on two cores; what runs and why is in docs/RELIABILITY.md.
set -uo pipefail

. "$(dirname "$0")/build_dir.sh"
require_build rusticl.sh "$@"
# Rusticl lists no device unless a driver is enabled by name.
export RUSTICL_ENABLE=llvmpipe
export POCL_CACHE_DIR="$build/pocl-cache"
if ! "$build/opsila" devices 2>/dev/null | grep -q "platform: rusticl"; then
  echo "rusticl.sh: no Rusticl device (apt-get install mesa-opencl-icd)" >&2
  exit 2
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
start=$(date +%s)

echo "-- tests on Rusticl"
OPSILA_TEST_DEVICE=rusticl "$build/opsila_tests" --gtest_brief=1 \
  --gtest_filter='Renderer.*:Spp*:SurfaceRender*:HitOrderRender*:HitOrderKernel*:Instances.*:HugeValues.*:DeviceArithmetic.*:Determinism.PrimaryDescriptorsBuiltAhead*:Determinism.LaunchesWithoutEvents*:DeviceResolve.*:QuantisedNodes.*:BankBvhWalk.*' >"$work/tests.log" 2>&1 || failed=1
grep -E '^\[  (PASSED|FAILED|SKIPPED) |^\[  FAILED  \]|tests? ran' "$work/tests.log" | sed 's/^/    /'
[ $failed -eq 0 ] || tail -n 60 "$work/tests.log"

# The 8-bit image; the linear floats may differ in their last bits (the
# compilers order and contract float operations differently).
echo "-- a gallery scene on Rusticl and on PoCL: the same PNG"
for device in rusticl pocl; do
  "$build/opsila" render "$root/scenes/whitted.json" --size 160x120 --device "$device" -q \
    -o "$work/$device.png" >"$work/$device.out" 2>&1 || { failed=1; cat "$work/$device.out"; }
done
if cmp -s "$work/rusticl.png" "$work/pocl.png"; then
  echo "    whitted.json 160x120: identical"
else
  echo "    FAIL: whitted.json's PNG differs between Rusticl and PoCL"
  failed=1
fi

echo "rusticl.sh: $([ $failed -eq 0 ] && echo passed || echo FAILED) in $(($(date +%s) - start)) s"
exit $failed
