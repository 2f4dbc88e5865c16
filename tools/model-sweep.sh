#!/usr/bin/env bash
# The determinism sweep over real models: every model file under a folder
# (default: Debian's assimp-testmodels) rendered at 1 PE, then again at 16
# PEs, at 64 PEs balanced by sampled work, and at 7 PEs balanced by measured
# work with the paper's bounding spheres for routing; each image must be the
# first one's bytes (docs/RELIABILITY.md, "Deterministic images"). With
# RANKS set (e.g. RANKS="2 3"), each model is also rendered on that many MPI
# ranks at 16 PEs. MODES replaces the three modes (flag sets separated by
# ';'), and FLAGS is added to every render, the first one's too, e.g.
#   FLAGS="--spp 4 --depth 7" MODES="--pes 5 --bank-capacity 4;--pes 33 --work-groups-per-pe 1" \
#     tools/model-sweep.sh
# A model opsila refuses is listed with its error, not
# counted as a failure: the sweep is about the images of the models that
# load.
#
#   tools/model-sweep.sh [FOLDER] [SIZE]     # SIZE default 96x72
#
# Prints one line a model (OK, DIFF with the mode, FAIL with the exit code,
# REFUSED with the error) and a summary; exits 1 if any DIFF or FAIL.
set -u
folder=${1:-/usr/share/assimp/models}
size=${2:-96x72}
root=$(cd "$(dirname "$0")/.." && pwd)
opsila=${OPSILA:-$root/build/opsila}
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$root/build/pocl-cache}
[ -x "$opsila" ] || { echo "model-sweep: no $opsila (build first)" >&2; exit 2; }
[ -d "$folder" ] || { echo "model-sweep: no folder $folder" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

modes=("--pes 16" "--pes 64 --balance work" "--pes 7 --balance measured --routing spheres")
if [ -n "${MODES:-}" ]; then IFS=';' read -r -a modes <<<"$MODES"; fi
read -r -a common <<<"${FLAGS:-}"

ok=0 bad=0 refused=0
while IFS= read -r -d '' model; do
  if ! timeout 300 "$opsila" render "$model" -o "$work/one.pfm" --size "$size" --pes 1 "${common[@]}" -q 2>"$work/err" </dev/null; then
    echo "REFUSED $model: $(head -c 200 "$work/err" | tr '\n' ' ')"
    refused=$((refused + 1))
    continue
  fi
  runs=()
  for m in "${modes[@]}"; do runs+=("$m"); done
  for r in ${RANKS:-}; do runs+=("ranks $r"); done
  good=1
  for run in "${runs[@]}"; do
    if [[ $run == ranks* ]]; then
      cmd=(mpirun --oversubscribe -np "${run#ranks }" "$opsila" render "$model" --pes 16)
    else
      read -r -a flags <<<"$run"
      cmd=("$opsila" render "$model" "${flags[@]}")
    fi
    timeout 600 "${cmd[@]}" -o "$work/other.pfm" --size "$size" "${common[@]}" -q 2>"$work/err" </dev/null
    rc=$?
    if [ $rc -ne 0 ]; then
      echo "FAIL ($rc) [$run] $model: $(head -c 200 "$work/err" | tr '\n' ' ')"
      good=0
    elif ! cmp -s "$work/one.pfm" "$work/other.pfm"; then
      echo "DIFF [$run] $model"
      good=0
    fi
  done
  if [ $good = 1 ]; then echo "OK $model"; ok=$((ok + 1)); else bad=$((bad + 1)); fi
done < <(find "$folder" -type f \( -iname '*.obj' -o -iname '*.ply' -o -iname '*.stl' -o -iname '*.off' \
  -o -iname '*.gltf' -o -iname '*.glb' -o -iname '*.fbx' -o -iname '*.dae' -o -iname '*.3ds' -o -iname '*.ase' \
  -o -iname '*.lwo' -o -iname '*.x' -o -iname '*.ac' -o -iname '*.ms3d' -o -iname '*.nff' -o -iname '*.blend' \
  -o -iname '*.amf' \) -print0 | sort -z)
echo "model-sweep: $ok models the same bytes in every mode, $bad not, $refused refused"
[ $bad = 0 ]
