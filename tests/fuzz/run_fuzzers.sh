#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in build-fuzz and runs
# each one on a copy of its seed corpus.
# Exits non-zero if the build fails or any fuzzer finds a crash, a leak, a
# timeout (-timeout=10) or an out-of-memory input (-rss_limit_mb=2048);
# the offending inputs are left in build-fuzz/fuzz-NAME/artifacts/.
#
#   tests/fuzz/run_fuzzers.sh [SECONDS]   explore: a random seed, SECONDS per
#                                         target (default 60; the model target
#                                         a third of it, at most 20 s)
#   tests/fuzz/run_fuzzers.sh --ci        the CI run: a fixed seed and a fixed
#                                         number of inputs per target (runs
#                                         still differ a little: coverage
#                                         feedback inside the libraries is
#                                         not exactly repeatable); what
#                                         exploring finds joins the corpora
#                                         (tests/fuzz/corpus_*)
set -uo pipefail

ci=0
seconds=60
if [ "${1:-}" = "--ci" ]; then
  ci=1
elif [ $# -gt 0 ]; then
  seconds="$1"
fi
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ] || [ $# -gt 1 ]; then
  echo "usage: $0 [SECONDS | --ci]  (SECONDS a positive whole number, default 60)" >&2
  exit 2
fi
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$root/build-fuzz"
cxx="${FUZZ_CXX:-clang++}"
if ! command -v "$cxx" >/dev/null; then
  echo "$cxx not found: the fuzzers need clang (apt-get install clang libclang-rt-14-dev)" >&2
  exit 2
fi

# -fsanitize=fuzzer-no-link gives the library coverage instrumentation, so
# the fuzzer is guided by the loaders' code and not just the entry point.
cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DOPSILA_FUZZ=ON -DOPSILA_BUILD_TESTS=OFF -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" \
  || exit 1
cmake --build "$build" -j"$(nproc)" --target fuzz_obj fuzz_scene fuzz_model || exit 1

# Leaks inside third-party libraries (the Open Asset Import Library) are
# suppressed as in the sanitizer run; project code gets none (.ci/lsan.supp).
export LSAN_OPTIONS="suppressions=$root/.ci/lsan.supp:print_suppressions=0"

# A small stack for the targets (2 MiB, a quarter of the usual default):
# recursion that grows with the input must be bounded by the checks, and
# the model importer's own runs on its thread with a stack of its own
# (formats/common/model_files.h), which this limit does not reach.
ulimit -s 2048 || exit 1

# The model importer's memory budget (OPSILA_IMPORT_MEMORY), half the
# fuzzers' limit: the glTF checks must refuse what the importer would take
# beyond it, so that no input reaches -rss_limit_mb.
export OPSILA_IMPORT_MEMORY=$(( 1 << 30 ))

status=0
for name in obj scene model; do
  work="$build/fuzz-$name"
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp "$root/tests/fuzz/corpus_$name/"* "$work/corpus/"
  if [ "$ci" = 1 ]; then
    # About a minute each on one core (the model target is slower per input);
    # the time cap only guards a much slower machine.
    case "$name" in
      obj) limit=(-seed=1 -runs=1000000) ;;
      scene) limit=(-seed=1 -runs=600000) ;;
      model) limit=(-seed=1 -runs=30000) ;;
    esac
    limit+=(-max_total_time=600)
    echo "== fuzz_$name: ${limit[*]}"
  else
    # The model target mostly exercises the importer library; a third of the
    # time (at most 20 s) covers the conversion layer on top of it.
    run_seconds=$seconds
    if [ "$name" = model ]; then run_seconds=$(( seconds / 3 > 20 ? 20 : (seconds / 3 > 0 ? seconds / 3 : 1) )); fi
    limit=(-max_total_time="$run_seconds")
    echo "== fuzz_$name for ${run_seconds}s"
  fi
  "$build/fuzz_$name" "$work/corpus" "${limit[@]}" -rss_limit_mb=2048 -timeout=10 \
    -dict="$root/tests/fuzz/$name.dict" -artifact_prefix="$work/artifacts/" -print_final_stats=1 \
    >"$work/log.txt" 2>&1
  rc=$?
  grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb)" "$work/log.txt" || true
  if [ "$rc" -ne 0 ] || [ -n "$(ls -A "$work/artifacts")" ]; then
    echo "fuzz_$name FAILED (exit $rc); log: $work/log.txt; inputs: $work/artifacts/" >&2
    tail -n 40 "$work/log.txt" >&2
    status=1
  else
    echo "fuzz_$name: no findings"
  fi
done
exit "$status"
