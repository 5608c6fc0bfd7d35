#!/bin/sh
# The GPU numbers of issues #3 and #4, run on the GPU server from the checkout
# root after prepare.sh (the device tool: carry .gl and .whl). Writes JSON and
# text reports to $OUT (default ./gpu-results). Usage: measure.sh [timings|draws|converge|all]
# (one device call is limited to 10 minutes: run `timings` and `converge` apart).
set -eu
part=${1:-all}
out=${OUT:-gpu-results}
mkdir -p "$out"
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
[ -d /tmp/site/moderngl ] || python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl
export PYTHONPATH="/tmp/site:$PWD/app"
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
es() { python3 -m envstudio "$@"; }
if [ "$part" = timings ] || [ "$part" = all ]; then
# kautz static single pass against mirror (#4: <= 1.2x), 1080p, 100k triangles
es bench --methods mirror,kautz --size 1920x1080 --triangles 100000 --json "$out/bench.json" \
    | tee "$out/bench.txt"
# kautz dynamic update of a 256² cube, per pass (#4: under 1 ms in all)
for mips in false true; do
    es bench --scene room --methods kautz --size 640x360 --param dynamic=true \
        --param cross_face_filter=$mips --json "$out/dynamic_cross_$mips.json" \
        | tee "$out/dynamic_cross_$mips.txt"
done
fi
if [ "$part" = draws ] || [ "$part" = all ]; then
# the reference's batch in one draw (0) or in draws of k samples per pixel: about
# 10 000 reflector pixels leave a large GPU mostly idle, more draws in flight may not
for k in 0 1 2 4 8; do
    es bench --scene studio --methods reference --size 256x256 --param samples_per_draw=$k \
        --json "$out/draws_$k.json" | tee "$out/draws_$k.txt"
done
fi
if [ "$part" = converge ] || [ "$part" = all ]; then
# time to a converged reference at 256² (#3); --resume keeps the accumulation in
# .gpu-cache/ (git-ignored, kept on a warm device between calls), so a run cut
# by CONVERGE_LIMIT continues in the next `converge` call and counts all its seconds.
# CONVERGE_PARAMS adds --param options that leave the estimate and its saved key
# alone, e.g. "--param samples_per_draw=2" (the fastest of `draws`).
# The saved accumulations also come back in $out/cache/: copied into the
# workstation's .gpu-cache/reference/ and carried (carry .gpu-cache), they let a
# run continue on a fresh machine, in a later session (README.md beside this file).
export ENVSTUDIO_CACHE_DIR="$PWD/.gpu-cache"
for scene in ${CONVERGE_SCENES:-studio room}; do
    es bench --converge --resume --scene "$scene" --size 256x256 --param max_samples=10000000 \
        --time-limit "${CONVERGE_LIMIT:-200}" ${CONVERGE_PARAMS:-} --json "$out/converge_$scene.json" \
        | tee "$out/converge_$scene.txt"
    mkdir -p "$out/cache"
    cp "$ENVSTUDIO_CACHE_DIR"/reference/*.npz "$out/cache/"
done
fi
