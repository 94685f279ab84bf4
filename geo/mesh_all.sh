#!/usr/bin/env bash
# Mesh every geo/*.geo script at the given refinement levels.
#
# usage: geo/mesh_all.sh OUTDIR [LEVELS...]        (default levels: 0 1 2)
#
# Writes OUTDIR/<script>_l<level>.msh (MSH 4.1 ASCII) and prints one line per
# mesh: name, dimension, node count, element count (all saved elements,
# boundary elements included), wall time. Works from any directory. Exits
# non-zero if any gmsh run fails (its first errors are printed and the
# partial .msh is removed). The gmsh
# executable can be overridden with the GMSH environment variable.
set -u

if [ $# -lt 1 ] || [ "$1" = "-h" ] || [ "$1" = "--help" ]; then
  echo "usage: $0 OUTDIR [LEVELS...]   (default levels: 0 1 2)" >&2
  exit 2
fi

GEO_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
GMSH="${GMSH:-gmsh}"
OUTDIR="$1"; shift
if [ $# -gt 0 ]; then LEVELS=("$@"); else LEVELS=(0 1 2); fi

command -v "$GMSH" >/dev/null 2>&1 || { echo "error: '$GMSH' not found" >&2; exit 2; }
mkdir -p "$OUTDIR" || exit 2
OUTDIR="$(cd "$OUTDIR" && pwd)"
LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

# count nodes / elements from the $Nodes / $Elements headers of an MSH 4.1 file
msh_counts() {
  awk '/^\$Nodes/ {getline; n=$2} /^\$Elements/ {getline; e=$2} END {print n+0, e+0}' "$1"
}

shopt -s nullglob
scripts=("$GEO_DIR"/*.geo)
[ ${#scripts[@]} -gt 0 ] || { echo "error: no .geo scripts in $GEO_DIR" >&2; exit 2; }

failed=()
printf '%-28s %3s %9s %10s %9s\n' "mesh" "dim" "nodes" "elements" "seconds"
for geo in "${scripts[@]}"; do
  name="$(basename "$geo" .geo)"
  # 3D scripts define physical volumes, 2D scripts only physical surfaces
  if grep -q '^[[:space:]]*Physical Volume' "$geo"; then dim=3; else dim=2; fi
  for level in "${LEVELS[@]}"; do
    out="$OUTDIR/${name}_l${level}.msh"
    rm -f "$out"
    t0=$(date +%s.%N)
    "$GMSH" "-$dim" "$geo" -setnumber level "$level" -format msh41 -o "$out" >"$LOG" 2>&1
    rc=$?
    t1=$(date +%s.%N)
    secs=$(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.2f", b - a}')
    if [ $rc -ne 0 ] || grep -q '^Error' "$LOG" || [ ! -s "$out" ]; then
      printf '%-28s %3s %9s %10s %9s  FAILED (gmsh exit %d)\n' "${name}_l${level}" "$dim" "-" "-" "$secs" "$rc"
      { grep -m 8 '^Error' "$LOG" || tail -n 8 "$LOG"; } | sed 's/^/    /'
      rm -f "$out"
      failed+=("${name}_l${level}")
      continue
    fi
    read -r nn ne < <(msh_counts "$out")
    printf '%-28s %3s %9d %10d %9s\n' "${name}_l${level}" "$dim" "$nn" "$ne" "$secs"
  done
done

if [ ${#failed[@]} -gt 0 ]; then
  echo "FAILED: ${failed[*]}" >&2
  exit 1
fi
