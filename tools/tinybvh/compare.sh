#!/usr/bin/env bash
# The traversal alone against tinybvh's OpenCL kernels on the same rays
# (docs/BENCHMARKS.md, "Against another OpenCL traversal"):
#   build/opsila bench scenes/crowd.json --rays-out crowd.rays
#   tools/tinybvh/compare.sh crowd.rays [TINYBVH_DIR]
# Without TINYBVH_DIR it clones tinybvh (network) at the commit of its
# release 1.6.7 that the figures used, into build/tinybvh. Time on a quiet
# machine, alternating with the bench; the device is the first OpenCL
# device (as the bench's default), POCL_CACHE_DIR as you set it.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
[[ $# -ge 1 ]] || { echo "usage: $0 FILE.rays [TINYBVH_DIR]" >&2; exit 2; }
rays="$1"
tinybvh="${2:-$root/build/tinybvh}"
commit=4735685f64d8b2bb0ad2c6c4643f291bf58774ad
if [[ ! -f "$tinybvh/tiny_bvh.h" ]]; then
  git clone -q https://github.com/jbikker/tinybvh "$tinybvh"
  git -C "$tinybvh" checkout -q "$commit"
fi
out="$root/build/tinybvh-harness"
mkdir -p "$out"
cp "$here/harness.cl" "$out/"
# -fno-strict-aliasing: tinybvh 1.6.7 writes its 4-wide GPU layout's leaf
# flags through a float pointer; at -O2 GCC 12 loses them and every ray misses.
g++ -O2 -march=native -fno-strict-aliasing -std=c++17 -w -I"$tinybvh" "$here/harness.cpp" -o "$out/harness" -lOpenCL
"$out/harness" "$rays" "$tinybvh" "${3:-9}"
