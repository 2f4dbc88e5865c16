#!/usr/bin/env bash
# Runs the OpenCL kernels under Oclgrind (an OpenCL device simulator that
# checks every memory access) and fails on ANY finding: out-of-bounds or
# invalid accesses, data races, uses of uninitialized values, API misuse.
#
#   .ci/oclgrind.sh BUILD_DIR
#
# BUILD_DIR is a normal build (not OPSILA_SANITIZE) holding `opsila` and
# `opsila_tests`. Needs Debian's `oclgrind` package. Takes about a minute
# or two: Oclgrind is about 1000x slower than a real device, so the scenes
# are tiny. What runs, and why the flags differ, is in docs/RELIABILITY.md.
set -uo pipefail

. "$(dirname "$0")/build_dir.sh"
require_build oclgrind.sh "$@"
command -v oclgrind >/dev/null || { echo "oclgrind.sh: 'oclgrind' not found (apt-get install oclgrind)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene="$root/tests/oclgrind/tiny.obj"
view=(--light 2,5,4 --light -3,4,1,0.4,0.4,0.5 --eye 1.5,2.2,5 --look-at 0,0.8,0)
# Every check Oclgrind has. --uninitialized needs unoptimised code: Oclgrind
# 21.10's uninitialized-value plugin stops at LLVM's `freeze` instruction,
# which optimised builds contain; the other checks also run on optimised code.
all_checks=(--data-races --uninitialized --check-api --build-options -cl-opt-disable)
optimised_checks=(--data-races --check-api)
failed=0
start_all=$(date +%s)

# check NAME OCLGRIND_OPTIONS... -- COMMAND...
check() {
  local name=$1
  shift
  local options=()
  while [ "$1" != "--" ]; do
    options+=("$1")
    shift
  done
  shift
  local log="$work/$name.oclgrind.log" out="$work/$name.out" start=$(date +%s) rc=0
  # Oclgrind's findings go to --log; the program's own output to $out.
  POCL_CACHE_DIR="$work/pocl-cache" oclgrind "${options[@]}" --log "$log" "$@" >"$out" 2>&1 || rc=$?
  local seconds=$(($(date +%s) - start)) problems=""
  [ "$rc" -eq 0 ] || problems+=" exit status $rc;"
  [ ! -s "$log" ] || problems+=" Oclgrind findings;"
  # Backstop, should Oclgrind print anything past its log.
  if grep -Eiq 'oclgrind|invalid (read|write)|data race|uninitiali[sz]ed|out of bounds|fatal' "$out"; then
    problems+=" Oclgrind messages in the output;"
  fi
  if [ -n "$problems" ]; then
    echo "FAIL  $name (${seconds}s):$problems"
    [ ! -s "$log" ] || head -n 60 "$log" | sed 's/^/    /'
    tail -n 30 "$out" | sed 's/^/    | /'
    failed=1
  else
    echo "ok    $name (${seconds}s)"
  fi
}

# 1. A render with every check: 8x6 pixels, depth 3, 4 PEs, a mirror, a
#    closed glass box, two lights (shadow rays cross PEs).
check render-all-checks "${all_checks[@]}" -- \
  "$build/opsila" render "$scene" -o "$work/render.pfm" --size 8x6 --depth 3 --pes 4 --device oclgrind -q "${view[@]}"

# 2. The same scene on optimised kernels (what drivers run), depth 4, one
#    descriptor slot per bank: every overflow, queue and regrowth path.
check render-optimised-tiny-banks "${optimised_checks[@]}" -- \
  "$build/opsila" render "$scene" -o "$work/banks.pfm" --size 8x6 --depth 4 --pes 4 --bank-capacity 1 \
  --device oclgrind -q "${view[@]}"

# 2a. More hits than one injection (1024) and small banks: the SPMD launch's
#     work-groups build the next round's primary descriptors beside the
#     phase's (kernels/spmd_phase.cl), every check.
check render-primary-ahead-all-checks "${all_checks[@]}" -- \
  "$build/opsila" render "$scene" -o "$work/ahead.pfm" --size 48x32 --depth 2 --pes 4 --bank-capacity 8 \
  --device oclgrind -q "${view[@]}"

# 2b. Samples per pixel (k = 2): the centre-only item-buffer pass, one pass
#     per sample, the primary hit counter.
check render-spp-all-checks "${all_checks[@]}" -- \
  "$build/opsila" render "$scene" -o "$work/spp.pfm" --size 4x3 --depth 2 --pes 4 --spp 4 --device oclgrind -q \
  "${view[@]}"

# 2b'. A GPU's paths on a device that shares host memory: launches without
#      events but the long ones (OPSILA_LAUNCH_EVENTS=0), the image
#      resolved on the device (kernels/resolve.cl) and the bank walks on
#      quantised nodes (OPSILA_QUANT_NODES=1), every check; its image is
#      render-all-checks' to the byte.
check render-gpu-paths-all-checks "${all_checks[@]}" -- \
  env OPSILA_LAUNCH_EVENTS=0 OPSILA_DEVICE_RESOLVE=1 OPSILA_QUANT_NODES=1 "$build/opsila" render "$scene" -o "$work/resolved.pfm" \
  --size 8x6 --depth 3 --pes 4 --device oclgrind -q "${view[@]}" --stats "$work/resolved.json"
if ! grep -q '"resolve_image"' "$work/resolved.json" 2>/dev/null || ! cmp -s "$work/render.pfm" "$work/resolved.pfm"; then
  echo "FAIL  render-gpu-paths: no resolve_image launch, or not render-all-checks' image"
  failed=1
fi

# 2c. Texture maps and smooth shading: vertex attributes, texture copies in
#     the banks, texel lookups and the sRGB table.
check render-textured-smooth-all-checks "${all_checks[@]}" -- \
  "$build/opsila" render "$root/tests/oclgrind/textured.obj" -o "$work/textured.pfm" --size 6x4 --depth 2 --pes 4 \
  --smooth --device oclgrind -q "${view[@]}"

# 2d. --balance measured: the pilot frames' program (OPSILA_MEASURE_COST),
#     which counts every test of the SPMD phase per cluster and level, with
#     every check on one pilot machine; then the whole flow (five pilot
#     machines, then the frame's) on optimised kernels. Not the whole flow
#     with --uninitialized: Oclgrind 21.10 then reports the next machine's
#     buffers, allocated where the last one's were, as never written
#     (docs/RELIABILITY.md).
check pilot-all-checks "${all_checks[@]}" -- \
  env OPSILA_TEST_DEVICE=oclgrind "$build/opsila_tests" --gtest_filter='Pilot.*'
check render-measured-balance-optimised "${optimised_checks[@]}" -- \
  "$build/opsila" render "$scene" -o "$work/measured.pfm" --size 6x4 --depth 2 --pes 4 --balance measured \
  --device oclgrind -q "${view[@]}"

# 2e. Instances (-DOPSILA_INSTANCES=1): walks into a model's BVH in its
#     frame, instance hits in the item buffer's keys and the descriptors,
#     a model copy shared by the banks; with every check, then optimised
#     with one descriptor slot per bank, on quantised nodes.
check render-instances-all-checks "${all_checks[@]}" -- \
  "$build/opsila" render "$root/tests/oclgrind/instances.json" -o "$work/instances.pfm" --size 8x6 --depth 3 \
  --pes 4 --device oclgrind -q "${view[@]}"
check render-instances-optimised "${optimised_checks[@]}" -- \
  env OPSILA_QUANT_NODES=1 "$build/opsila" render "$root/tests/oclgrind/instances.json" -o "$work/instances-banks.pfm" --size 8x6 --depth 4 \
  --pes 4 --bank-capacity 1 --device oclgrind -q "${view[@]}"

# 3. The scatter on its own: SPMD output slots with holes and unused slots,
#    a waiting queue, banks that overflow (tests/frame/small_scatter_test.cpp).
check scatter-all-checks "${all_checks[@]}" -- \
  env OPSILA_TEST_DEVICE=oclgrind "$build/opsila_tests" --gtest_filter='SmallScatter.*'
check scatter-optimised "${optimised_checks[@]}" -- \
  env OPSILA_TEST_DEVICE=oclgrind "$build/opsila_tests" --gtest_filter='SmallScatter.*'

# 3b. GPU-like: work-groups of 256 work-items (OPSILA_GROUP_SIZE; 64 is the
#     default) on a simulated device with a typical GPU's 48 KiB of local
#     memory and at most 1024 work-items per group. Barriers, work-group
#     arrays and the exchange's scan and plan then span 256 work-items, most
#     of them idle in a small frame.
gpu_like=(--max-wgsize 1024 --local-mem-size 49152)
check render-gpu-like-all-checks "${all_checks[@]}" "${gpu_like[@]}" -- \
  env OPSILA_GROUP_SIZE=256 "$build/opsila" render "$scene" -o "$work/gpu.pfm" --size 16x16 --depth 3 --pes 4 \
  --device oclgrind -q "${view[@]}"
check render-gpu-like-tiny-banks-optimised "${optimised_checks[@]}" "${gpu_like[@]}" -- \
  env OPSILA_GROUP_SIZE=256 "$build/opsila" render "$scene" -o "$work/gpu-banks.pfm" --size 8x6 --depth 4 --pes 4 \
  --bank-capacity 1 --device oclgrind -q "${view[@]}"
check scatter-gpu-like-all-checks "${all_checks[@]}" "${gpu_like[@]}" -- \
  env OPSILA_GROUP_SIZE=256 OPSILA_TEST_DEVICE=oclgrind "$build/opsila_tests" --gtest_filter='SmallScatter.*'

# 4. Sanity: the simulated render is the image a real device makes (when
#    there is one besides Oclgrind): same scene, 40 dB or better.
if [ -s "$work/render.pfm" ] && command -v python3 >/dev/null &&
  POCL_CACHE_DIR="$work/pocl-cache" "$build/opsila" render "$scene" -o "$work/native.pfm" --size 8x6 --depth 3 \
    --pes 4 -q "${view[@]}" >"$work/native.out" 2>&1; then
  if python3 - "$work/render.pfm" "$work/native.pfm" <<'EOF'; then
import math, struct, sys
def read(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    little = float(parts[2]) < 0
    return struct.unpack(("<" if little else ">") + "%df" % (3 * w * h), parts[3][: 12 * w * h])
a, b = read(sys.argv[1]), read(sys.argv[2])
clamp = lambda v: min(1.0, max(0.0, v))
mse = sum((clamp(x) - clamp(y)) ** 2 for x, y in zip(a, b)) / len(a)
psnr = float("inf") if mse == 0 else 10 * math.log10(1 / mse)
print("      Oclgrind vs native device: %.1f dB" % psnr)
sys.exit(0 if psnr >= 40 else 1)
EOF
    echo "ok    image-matches-native"
  else
    echo "FAIL  image-matches-native: the Oclgrind render differs from the native one"
    failed=1
  fi
else
  echo "skip  image-matches-native (no native device or no python3)"
fi

echo "oclgrind.sh: $([ $failed -eq 0 ] && echo clean || echo FINDINGS) in $(($(date +%s) - start_all)) s"
exit $failed
