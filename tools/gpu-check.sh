#!/usr/bin/env bash
# The GPU check: opsila run on a machine with a GPU, its vendor's OpenCL
# driver, a compiler and CMake, but no Debian development packages and no
# network. Two steps:
#
#   tools/gpu-check.sh pack [KIT]   on a machine set up by tools/setup.sh
#       (PoCL), after a build: copies the header-only dependencies (OpenCL C
#       and C++ headers, nlohmann/json, stb_image(_write), tinyobjloader) into
#       KIT/include, renders the gallery with PoCL into KIT/pocl/*.pfm, and
#       packs the Debian build: build/opsila and build/opsila_tests with the
#       shared libraries they load (all but the C library's, which any newer
#       glibc serves) and the assimp test models the tests and scenes read.
#   tools/gpu-check.sh run [KIT]    on the GPU machine, with KIT copied along:
#       registers the NVIDIA OpenCL driver when no ICD file names it, then
#       1. the Debian build: `opsila devices`; the gallery at 1, 16 and 64 PEs
#          on the default device (the first GPU), each image byte-identical
#          across PE counts and from run to run, and compared with PoCL's;
#          the test suite on that device (OPSILA_TEST_DEVICE, default: the
#          default device), all but the MPI tests (no launcher there), four
#          shards side by side;
#       2. the build from source: builds opsila in build-gpu against KIT
#          (tests, Embree and other optional parts off) while 1 runs, and
#          checks that its image of the default scene is the Debian build's;
#       3. `opsila bench` on hundreds at 800x600 and 1920x1080 (the Debian
#          build, Embree beside it on the host's threads), and renders at
#          1920x1080 with and without OPSILA_PRIMARY_AHEAD,
#          OPSILA_LAUNCH_EVENTS, OPSILA_DEVICE_RESOLVE and OPSILA_QUANT_NODES.
#       Everything runs within 8 minutes.
#
# KIT defaults to ./gpu-kit. Results: KIT/results (log, PFMs, bench JSON and
# text, test logs). The image check is the one the tests hold the renderer
# to (README, "Tests and CI"): PSNR >= 40 dB and at most 0.5% of pixels off
# by more than 2/255 in any channel, values clamped to [0, 1]. It prints both.
# The Debian build needs a glibc at least as new as Debian 12's (2.36).
set -uo pipefail
cd "$(dirname "$0")/.."
root=$PWD
mode=${1:-}
kit=$(realpath -m "${2:-gpu-kit}")
start=$SECONDS builder= driver_dir= gpu_libs=
# Gallery: scene and the size of the check (small enough to carry the PFMs).
gallery=("default 320x240" "cornell 320x240" "whitted 320x240" "hundreds 320x240" "million 320x240"
  "crowd 320x240" "smooth 320x240" "textured 320x240")
models=/usr/share/assimp/models  # Debian's assimp-testmodels: scenes/textured.json and tests read them

die() {
  echo "gpu-check: $*" >&2
  exit 2
}

pack() {
  [ -x build/opsila ] && [ -x build/opsila_tests ] || die "build opsila and its tests first (tools/setup.sh)"
  rm -rf "$kit" && mkdir -p "$kit/include/stb" "$kit/pocl" "$kit/debian"
  cp -r /usr/include/CL /usr/include/nlohmann "$kit/include/" || die "missing Debian headers"
  cp /usr/include/stb/stb_image_write.h /usr/include/stb/stb_image.h "$kit/include/stb/" || die "missing libstb-dev"
  cp /usr/include/tiny_obj_loader.h "$kit/include/" || die "missing libtinyobjloader-dev"
  for entry in "${gallery[@]}"; do
    set -- $entry
    POCL_CACHE_DIR="$root/build/pocl-cache" build/opsila render "scenes/$1.json" --size "$2" --device pocl -q \
      -o "$kit/pocl/$1.pfm" || die "PoCL render of $1 failed"
  done
  # The Debian build and what it loads, but the C library (any newer glibc runs it).
  local lib=$kit/debian/lib
  mkdir -p "$lib"
  cp build/opsila build/opsila_tests "$kit/debian/"
  (ldd build/opsila; ldd build/opsila_tests) | awk '$3 ~ /^\// {print $3}' | sort -u | while read -r so; do
    case $(basename "$so") in libc.so.* | libm.so.* | ld-linux* | libpthread.so.* | libdl.so.* | librt.so.*) ;;
    *) cp -L "$so" "$lib/" ;;
    esac
  done
  tar -C "$kit/debian" -cJf "$kit/debian/lib.tar.xz" lib && rm -rf "$lib"
  [ -d "$models" ] && tar -C "$models" -cJf "$kit/debian/models.tar.xz" .
  echo "$root" >"$kit/debian/source_dir"  # the checkout the tests were built in (their data paths)
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
  driver_dir=$(dirname "$driver")
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

# 1. The Debian build from the kit: gallery and test suite on the default device.
debian_build() {
  local d=$kit/debian out=$1 packed failed=0 entry p
  [ -x "$d/opsila" ] || { echo "gpu-check: no Debian build in the kit; step 1 left out"; return 0; }
  gpu_libs=$(mktemp -d) && trap 'rm -rf "$gpu_libs"' EXIT && tar -C "$gpu_libs" -xJf "$d/lib.tar.xz" ||
    die "cannot unpack $d/lib.tar.xz"
  # The system's C++ runtime when it is at least Debian 12's (GCC 12).
  if grep -qs GLIBCXX_3.4.30 /usr/lib/x86_64-linux-gnu/libstdc++.so.6; then
    rm -f "$gpu_libs/lib/libstdc++.so.6" "$gpu_libs/lib/libgcc_s.so.1"
  fi
  export LD_LIBRARY_PATH="$gpu_libs/lib${driver_dir:+:$driver_dir}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  if [ ! -d "$models" ] && [ -f "$d/models.tar.xz" ]; then
    { mkdir -p "$models" && tar -C "$models" -xJf "$d/models.tar.xz"; } 2>/dev/null ||
      echo "gpu-check: cannot install the test models in $models (not root?): textured and model tests fail"
  fi
  # The tests read the checkout and run build/opsila at the paths they were built with.
  packed=$(cat "$d/source_dir")
  if [ "$packed" != "$root" ] && [ ! -e "$packed" ]; then
    { mkdir -p "$(dirname "$packed")" && ln -s "$root" "$packed"; } 2>/dev/null ||
      echo "gpu-check: cannot link $packed to this checkout: tests that read scenes fail"
  fi
  mkdir -p build
  for p in opsila opsila_tests; do
    if [ -e "build/$p" ] && ! cmp -s "build/$p" "$d/$p"; then
      echo "FAIL  build/$p is another build: run the check in a fresh copy of the checkout"
      return 1
    fi
    cp "$d/$p" build/
  done
  timeout 60 build/opsila devices || { echo "FAIL  opsila devices"; return 1; }
  mkdir -p "$out/debian"
  for entry in "${gallery[@]}"; do
    set -- $entry
    local same=ok
    for p in 16 1 64 16again; do
      if ! timeout 60 build/opsila render "scenes/$1.json" --size "$2" --pes "${p%again}" -q \
        -o "$out/debian/$1.$p.pfm" --stats "$out/debian/$1.$p.json"; then
        echo "FAIL  $1: render at ${p%again} PEs failed"
        failed=1
        same=
        break
      fi
      [ "$p" = 16 ] || cmp -s "$out/debian/$1.16.pfm" "$out/debian/$1.$p.pfm" || same="DIFFERS at $p PEs"
    done
    [ -n "$same" ] || continue
    [ "$same" = ok ] || { echo "FAIL  $1: 16 PEs vs $same"; failed=1; }
    if result=$(compare "$out/debian/$1.16.pfm" "$kit/pocl/$1.pfm"); then
      echo "ok    $1 (Debian build; byte-identical at 1, 16, 64 PEs and run to run) vs PoCL: $result"
    else
      echo "FAIL  $1 (Debian build) vs PoCL: $result"
      failed=1
    fi
  done
  local shards=4 i limit=$((300 - (SECONDS - start)))
  ((limit > 60)) || limit=60
  local pids=()
  for ((i = 0; i < shards; ++i)); do
    GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i timeout "$limit" build/opsila_tests \
      --gtest_filter='-MpiFixture.*' >"$out/tests.$i.txt" 2>&1 &
    pids+=($!)
  done
  wait "${pids[@]}"
  local logs=("$out"/tests.*.txt) ran passed skipped
  ran=$(cat "${logs[@]}" | grep -c -E '^\[==========\] .* ran')
  passed=$(grep -h -E '^\[  PASSED  \]' "${logs[@]}" | awk '{s += $4} END {print s + 0}')
  skipped=$(grep -h -E '^\[  SKIPPED \] [0-9]' "${logs[@]}" | awk '{s += $4} END {print s + 0}')
  if [ "$ran" != $shards ] || grep -qs -E '^\[  FAILED  \]' "${logs[@]}"; then
    echo "FAIL  tests on the default device (all but MPI): $ran of $shards shards ran to the end; failed:"
    grep -h -E '^\[  FAILED  \] [A-Z]' "${logs[@]}" | sort -u
    failed=1
  else
    echo "ok    tests on the default device (all but MPI): $passed passed, $skipped skipped (reasons in $out/tests.*.txt)"
  fi
  return $failed
}

# 2. The build from source against the kit's headers and the GPU machine's OpenCL library.
build_from_source() {
  unset LD_LIBRARY_PATH
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DOPSILA_BUILD_TESTS=OFF -DOPSILA_DEPS_DIR="$kit" \
    -DOpenCL_INCLUDE_DIR="$kit/include" -DOpenCL_LIBRARY="$1" -DCMAKE_DISABLE_FIND_PACKAGE_embree=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON -DCMAKE_DISABLE_FIND_PACKAGE_assimp=ON \
    -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON &&
    timeout 240 nice cmake --build build-gpu -j"$(nproc)" --target opsila
}

run() {
  [ -d "$kit/include" ] || die "no kit in $kit: run 'tools/gpu-check.sh pack' on a PoCL machine first"
  local out="$kit/results" failed=0 lib bin=build/opsila
  start=$SECONDS
  rm -rf "$out" && mkdir -p "$out"
  exec > >(tee "$out/log.txt") 2>&1
  lib=$(find_opencl)
  [ -n "$lib" ] || die "no libOpenCL found (CUDA's lib64 or the system's)"
  register_icd
  (build_from_source "$lib") >"$out/build.txt" 2>&1 &
  builder=$!
  debian_build "$out" || failed=1
  if wait "$builder" && [ -x build-gpu/opsila ]; then
    echo "gpu-check: built from source ($(grep -m1 'CXX compiler identification' "$out/build.txt" | sed 's/.*is //'))"
    [ -x build/opsila ] || bin=build-gpu/opsila
    if ! timeout 60 build-gpu/opsila render scenes/default.json --size 320x240 -q -o "$out/default.source.pfm"; then
      echo "FAIL  default: the build from source failed to render"
      failed=1
    elif [ -f "$out/debian/default.16.pfm" ]; then
      if cmp -s "$out/default.source.pfm" "$out/debian/default.16.pfm"; then
        echo "ok    default: the build from source gives the Debian build's image, byte for byte"
      else
        echo "note  default: the build from source differs from the Debian build (host compilers):" \
          "$(compare "$out/default.source.pfm" "$out/debian/default.16.pfm")"
      fi
    elif result=$(compare "$out/default.source.pfm" "$kit/pocl/default.pfm"); then
      echo "ok    default (build from source) vs PoCL: $result"
    else
      echo "FAIL  default (build from source) vs PoCL: $result"
      failed=1
    fi
  else
    echo "FAIL  the build from source (see $out/build.txt)"
    failed=1
  fi
  local size left
  for size in 800x600 1920x1080; do
    left=$((470 - (SECONDS - start)))
    ((left > 30)) || left=30
    if timeout "$left" "$bin" bench scenes/hundreds.json --size $size --repeats 3 --scatter-max 20 \
      --json "$out/bench.$size.json" >"$out/bench.$size.txt" 2>&1; then
      echo "ok    bench $size:"
      grep -E '^(OPSILA|replicated|Embree)|launch overhead  |of it: ' "$out/bench.$size.txt"
    else
      echo "FAIL  bench $size (or out of time)"
      failed=1
    fi
  done
  # Four levers, each on and off: the next round's primary descriptors
  # built by the SPMD launch (the default) or by a launch of their own
  # (OPSILA_PRIMARY_AHEAD=0); launches without events but the long ones
  # (OPSILA_LAUNCH_EVENTS=0, a plain render's way on a GPU) or every launch
  # timed (1); the image resolved on the GPU (OPSILA_DEVICE_RESOLVE=1, the
  # default there) or decoded on the host; the bank walks on quantised
  # nodes (OPSILA_QUANT_NODES=1, the default there) or float ones. Five
  # renders each at 1920x1080, interleaved; each run's frame seconds, and
  # whether the images are the same bytes.
  on_and_off OPSILA_PRIMARY_AHEAD
  on_and_off OPSILA_LAUNCH_EVENTS
  on_and_off OPSILA_DEVICE_RESOLVE
  on_and_off OPSILA_QUANT_NODES
  echo "gpu-check: $([ $failed -eq 0 ] && echo passed || echo FAILED) in $((SECONDS - start)) s; results in $out"
  return $failed
}

on_and_off() {  # on_and_off VARIABLE: renders with VARIABLE=1 and =0 (run, step 3)
  local var=$1 a i
  for a in 1 0; do : >"$out/$var$a.txt"; done
  for i in 1 2 3 4 5; do
    for a in 1 0; do
      env "$var=$a" timeout 60 "$bin" render scenes/hundreds.json --size 1920x1080 -q \
        -o "$out/$var$a.pfm" --stats "$out/$var$a.json" >/dev/null 2>&1 &&
        grep -o '"render_seconds": *[0-9.e+-]*' "$out/$var$a.json" | grep -o '[0-9.e+-]*$' >>"$out/$var$a.txt"
    done
  done
  for a in 1 0; do
    echo "      $var=$a, frame seconds (sorted): $(sort -g "$out/$var$a.txt" | tr '\n' ' ')"
  done
  cmp -s "$out/${var}1.pfm" "$out/${var}0.pfm" && echo "ok    $var=1 and =0 give the same image" ||
    { echo "FAIL  $var=1 and =0 give different images"; failed=1; }
}

case "$mode" in
  pack) pack ;;
  run) run ;;
  *) die "usage: tools/gpu-check.sh pack|run [KIT]" ;;
esac
