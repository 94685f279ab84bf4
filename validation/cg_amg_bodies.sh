#!/bin/sh
# internodes with every body solved by PETSc CG + AMG, whatever the case says: a stand-in
# binary for the validation scripts (--binary validation/cg_amg_bodies.sh) that runs a suite
# on the iterative body solver, e.g.
#
#   INTERNODES=target/release/internodes /usr/bin/python3 validation/sweep.py \
#       --binary validation/cg_amg_bodies.sh --out validation/build/sweep_cg_amg
#
# `solve CASE.toml ...` runs a copy of the case, beside it, with `[solver] body = "cg-amg"`
# (added to its [solver] table, or as one); every other command passes through.
set -eu
real=${INTERNODES:-target/release/internodes}
if [ "${1:-}" != solve ] || [ $# -lt 2 ]; then
    exec "$real" "$@"
fi
shift
case_file=$1
shift
copy="${case_file%.toml}.cg-amg.toml"
if grep -q '^\[solver\]' "$case_file"; then
    if grep -q '^body[[:space:]]*=' "$case_file"; then
        sed 's/^body[[:space:]]*=.*/body = "cg-amg"/' "$case_file" > "$copy"
    else
        sed 's/^\[solver\]$/[solver]\nbody = "cg-amg"/' "$case_file" > "$copy"
    fi
else
    { cat "$case_file"; printf '\n[solver]\nbody = "cg-amg"\n'; } > "$copy"
fi
exec "$real" solve "$copy" "$@"
