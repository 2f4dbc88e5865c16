# Sourced by the .ci scripts that take a BUILD_DIR holding `opsila` and
# `opsila_tests`: `require_build NAME "$@"` sets root (the sources) and
# build (absolute), or exits 2 with one line naming what is missing.
require_build() {
  local name=$1
  shift
  if [ $# -ne 1 ]; then
    echo "usage: $name BUILD_DIR" >&2
    exit 2
  fi
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  build=$(cd "$1" 2>/dev/null && pwd) || { echo "$name: no build folder '$1'" >&2; exit 2; }
  local bin
  for bin in opsila opsila_tests; do
    [ -x "$build/$bin" ] || { echo "$name: $build/$bin not built" >&2; exit 2; }
  done
}
