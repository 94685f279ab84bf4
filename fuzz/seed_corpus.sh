#!/bin/sh
# Seeds fuzz/corpus/read_msh with the test fixtures of at most 100 kB (ASCII and binary, 2D and
# 3D, sorted and shuffled node tags). Run from the repository root.
set -eu
mkdir -p fuzz/corpus/read_msh
for f in tests/fixtures/*.msh; do
    if [ "$(wc -c < "$f")" -le 102400 ]; then
        cp "$f" fuzz/corpus/read_msh/
    fi
done
ls fuzz/corpus/read_msh | wc -l
