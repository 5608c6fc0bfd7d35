#!/usr/bin/env bash
# The Phong methods' approximation error on the studio bunny at N = 200 against the exact
# reference, at each output size and footprint samples (README.md's table). Usage:
#   bash studies/rsibr-footprint/sweep.sh OUT_DIR
set -euo pipefail
out=${1:?usage: sweep.sh OUT_DIR}
mkdir -p "$out"
for case in "64x64 2" "128x128 1" "64x64 4" "96x96 2" "128x128 2" "96x96 4" "256x256 1"; do
    set -- $case
    envstudio compare --scene studio --methods mirror,kautz,hwconv,rsibr,parallax \
        --size "$1" --ssaa "$2" --param trace=false --param phong_exponent=200 \
        --out "$out/$1-$2" > "$out/$1-$2.txt" 2>&1
    printf '%s x%s:' "$1" "$2"
    grep '^| [a-z]' "$out/$1-$2.txt" | grep -v '^| method' | awk -F'|' '{printf " %s%s;", $2, $7}'
    echo
done
