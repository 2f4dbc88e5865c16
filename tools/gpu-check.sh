#!/usr/bin/env bash
# The GPU check: opsila built and run on a machine with a GPU, a compiler,
# CMake and the vendor's OpenCL runtime, but no Debian development packages
# and no network. Two steps:
#
#   tools/gpu-check.sh pack [KIT]   on a machine set up by tools/setup.sh
#       (PoCL): copies the header-only dependencies (OpenCL C and C++
#       headers, nlohmann/json, stb_image(_write), tinyobjloader) into
#       KIT/include and renders the gallery with PoCL into KIT/pocl/*.pfm.
#   tools/gpu-check.sh run [KIT]    on the GPU machine, with KIT copied along:
#       builds opsila in build-gpu against KIT (tests, Embree and other
#       optional parts off), registers the NVIDIA OpenCL driver when no ICD
#       file names it, runs `opsila devices`, renders the gallery on the
#       default device (the first GPU)
#       and compares each image with the PoCL one, then runs `opsila bench`
#       on hundreds at 1920x1080. Everything runs within 8 minutes.
#
# KIT defaults to ./gpu-kit. Results: KIT/results (log, PFMs, bench JSON).
# The image check is the one the tests hold the renderer to (README, "Tests
# and CI"): PSNR >= 40 dB and at most 0.5% of pixels off by more than 2/255
# in any channel, values clamped to [0, 1]. It prints both figures.
set -uo pipefail
cd "$(dirname "$0")/.."
root=$PWD
mode=${1:-}
kit=$(realpath -m "${2:-gpu-kit}")
# Gallery: scene and the size of the check (small enough to carry the PFMs).
gallery=("default 320x240" "cornell 320x240" "whitted 320x240" "hundreds 320x240" "million 320x240")

die() {
  echo "gpu-check: $*" >&2
  exit 2
}

pack() {
  [ -x build/opsila ] || die "build opsila first (tools/setup.sh)"
  rm -rf "$kit" && mkdir -p "$kit/include/stb" "$kit/pocl"
  cp -r /usr/include/CL /usr/include/nlohmann "$kit/include/" || die "missing Debian headers"
  cp /usr/include/stb/stb_image_write.h /usr/include/stb/stb_image.h "$kit/include/stb/" || die "missing libstb-dev"
  cp /usr/include/tiny_obj_loader.h "$kit/include/" || die "missing libtinyobjloader-dev"
  for entry in "${gallery[@]}"; do
    set -- $entry
    POCL_CACHE_DIR="$root/build/pocl-cache" build/opsila render "scenes/$1.json" --size "$2" --device pocl -q \
      -o "$kit/pocl/$1.pfm" || die "PoCL render of $1 failed"
  done
  echo "gpu-check: kit in $kit ($(du -sh "$kit" | cut -f1))"
}

# The OpenCL library and, when no ICD file names the NVIDIA driver, a private
# vendors folder that does (no root needed: both ICD loaders read it).
find_opencl() {
  for lib in /usr/local/cuda/lib64/libOpenCL.so /usr/local/cuda/lib64/libOpenCL.so.1 \
    /usr/lib/x86_64-linux-gnu/libOpenCL.so.1 /usr/lib64/libOpenCL.so.1 /usr/lib/libOpenCL.so.1; do
    [ -e "$lib" ] && { echo "$lib"; return 0; }
  done
  ldconfig -p 2>/dev/null | awk '/libOpenCL\.so/ {print $NF; exit}'
}

register_icd() {
  grep -qs nvidia /etc/OpenCL/vendors/*.icd && return 0
  local driver
  driver=$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ {print $NF; exit}')
  [ -n "$driver" ] || { echo "gpu-check: no libnvidia-opencl.so.1; using the ICDs present"; return 0; }
  mkdir -p "$kit/vendors"
  echo "$driver" >"$kit/vendors/nvidia.icd"
  export OCL_ICD_VENDORS="$kit/vendors" OCL_ICD_FILENAMES="$driver"
  echo "gpu-check: registered $driver"
}

compare() {  # compare A.pfm B.pfm -> prints the figures, fails outside the contract's tolerance
  python3 - "$1" "$2" <<'EOF'
import math, struct, sys
def read(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    little = float(parts[2]) < 0
    return w, h, struct.unpack(("<" if little else ">") + "%df" % (3 * w * h), parts[3][: 12 * w * h])
wa, ha, a = read(sys.argv[1])
wb, hb, b = read(sys.argv[2])
if (wa, ha) != (wb, hb):
    print("size differs"); sys.exit(1)
c = lambda v: min(1.0, max(0.0, v))
mse = sum((c(x) - c(y)) ** 2 for x, y in zip(a, b)) / len(a)
psnr = float("inf") if mse == 0 else 10 * math.log10(1 / mse)
off = sum(1 for i in range(0, len(a), 3) if max(abs(c(a[i + k]) - c(b[i + k])) for k in range(3)) > 2 / 255)
share = off / (wa * ha)
print("PSNR %s dB, %d pixels off (%.3f%%)" % ("inf" if psnr == float("inf") else "%.1f" % psnr, off, 100 * share))
sys.exit(0 if psnr >= 40 and share <= 0.005 else 1)
EOF
}

run() {
  [ -d "$kit/include" ] || die "no kit in $kit: run 'tools/gpu-check.sh pack' on a PoCL machine first"
  local start=$SECONDS out="$kit/results" failed=0 lib
  rm -rf "$out" && mkdir -p "$out"
  exec > >(tee "$out/log.txt") 2>&1
  lib=$(find_opencl)
  [ -n "$lib" ] || die "no libOpenCL found (CUDA's lib64 or the system's)"
  register_icd
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DOPSILA_BUILD_TESTS=OFF -DOPSILA_DEPS_DIR="$kit" \
    -DOpenCL_INCLUDE_DIR="$kit/include" -DOpenCL_LIBRARY="$lib" -DCMAKE_DISABLE_FIND_PACKAGE_embree=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON -DCMAKE_DISABLE_FIND_PACKAGE_assimp=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON >"$out/cmake.txt" ||
    die "cmake failed (see $out/cmake.txt)"
  timeout 240 cmake --build build-gpu -j"$(nproc)" --target opsila >"$out/build.txt" 2>&1 ||
    die "build failed (see $out/build.txt)"
  echo "gpu-check: built in $((SECONDS - start)) s"
  timeout 60 build-gpu/opsila devices || die "opsila devices failed"
  for entry in "${gallery[@]}"; do
    set -- $entry
    if ! timeout 60 build-gpu/opsila render "scenes/$1.json" --size "$2" -o "$out/$1.pfm" --stats "$out/$1.json"; then
      echo "FAIL  $1: render failed"
      failed=1
    elif result=$(compare "$out/$1.pfm" "$kit/pocl/$1.pfm"); then
      echo "ok    $1 vs PoCL: $result"
    else
      echo "FAIL  $1 vs PoCL: $result"
      failed=1
    fi
  done
  local left=$((480 - (SECONDS - start) - 10))
  ((left > 30)) || left=30
  timeout "$left" build-gpu/opsila bench scenes/hundreds.json --size 1920x1080 --repeats 3 --scatter-max 20 \
    --json "$out/bench.json" || { echo "FAIL  bench (or out of time)"; failed=1; }
  echo "gpu-check: $([ $failed -eq 0 ] && echo passed || echo FAILED) in $((SECONDS - start)) s; results in $out"
  return $failed
}

case "$mode" in
  pack) pack ;;
  run) run ;;
  *) die "usage: tools/gpu-check.sh pack|run [KIT]" ;;
esac
