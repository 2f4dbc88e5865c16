#!/usr/bin/env bash
# Builds everything with AddressSanitizer + UndefinedBehaviorSanitizer
# (-DOPSILA_SANITIZE=ON) in a separate build folder and runs the unit tests
# (ctest) under them. Any finding fails the run: UBSan and ASan stop the
# test that hits one, LeakSanitizer fails it at exit.
#
#   .ci/sanitize.sh [BUILD_DIR [CTEST_ARGS...]]   (default BUILD_DIR: build-asan in the sources)
#
# Every test runs; none needs leaving out (docs/RELIABILITY.md has the times).
# CTEST_ARGS are passed on, e.g. -R Renderer to run a subset.
#
# Leak suppressions (.ci/lsan.supp) name third-party libraries only (PoCL and
# its LLVM), never project code; docs/RELIABILITY.md says why.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build-asan}
if [ $# -gt 0 ]; then shift; fi
jobs=$(nproc 2>/dev/null || echo 2)
generator=()
if command -v ninja >/dev/null && [ ! -f "$build/CMakeCache.txt" ]; then generator=(-G Ninja); fi

start=$(date +%s)
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOPSILA_SANITIZE=ON >/dev/null
cmake --build "$build" -j "$jobs"
built=$(date +%s)

# intercept_tls_get_addr=0: LeakSanitizer (GCC 12's) then does not read the
# threads' dynamic TLS blocks through its own record of them, which held
# bogus ranges near address 0 in threads of PoCL's LLVM and made its tracer
# fault ("Tracer caught signal 11", 4 to 19 processes a CI run, no finding);
# the blocks are heap chunks reached from each thread's TLS all the same, so
# their pointers still count (docs/RELIABILITY.md).
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:intercept_tls_get_addr=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS=suppressions=$root/.ci/lsan.supp:print_suppressions=0
export POCL_CACHE_DIR=$build/pocl-cache
# Every OpenCL driver but Mesa's Clover (a platform with no device here):
# Clover reallocs 128 bytes inside a driver it loads and unloads while the
# platforms are listed, and the fast unwinder records that stack as
# "<unknown module>", which no suppression can name (recording whole stacks
# instead, fast_unwind_on_malloc=0, deadlocked against Rusticl's threads in
# libgcc's unwinder). Only the listing's check of Clover's empty platform
# is then left to the plain suite (docs/RELIABILITY.md).
vendors=$(mktemp -d)
trap 'rm -rf "$vendors"' EXIT
for icd in /etc/OpenCL/vendors/*.icd; do
  [ -e "$icd" ] || continue
  grep -q libMesaOpenCL "$icd" || cp "$icd" "$vendors/"
done
export OCL_ICD_VENDORS=$vendors

status=0
# --repeat until-pass:2: a test that fails is run once more (kept from the
# tracer crashes above, in case one is left); a real finding repeats and
# still fails (docs/RELIABILITY.md).
ctest --test-dir "$build" -j "$jobs" --output-on-failure --repeat until-pass:2 "$@" || status=$?
end=$(date +%s)
echo "sanitize.sh: build $((built - start)) s, tests $((end - built)) s: $([ $status -eq 0 ] && echo clean || echo FINDINGS OR FAILURES)"
exit $status
