#!/bin/sh
# Fetch what the GPU server lacks (../shared/GPU.md) into .gl/ and .whl/ at the
# checkout root, both git-ignored: the GL dispatch libraries from Debian and the
# CPython 3.12 wheels of every package the measured code paths import, at the
# versions of requirements.lock. Run on a machine with package access.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
mkdir -p .gl .whl /tmp/amd64/partial
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
# shellcheck disable=SC2086
apt-get $o update -qq
# shellcheck disable=SC2086
(cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
pinned() {
    for name in "$@"; do grep -i "^$name==" requirements.lock; done
}
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
    --implementation cp --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 --platform manylinux1_x86_64 --platform any -d .whl \
    $(pinned moderngl glcontext OpenImageIO trimesh scikit-image lazy-loader networkx \
        ImageIO tifffile packaging flip-evaluator embreex)
echo "ready: $(ls .gl | wc -l) packages in .gl, $(ls .whl | wc -l) wheels in .whl"
