#!/usr/bin/env bash
# Set up envmap-studio on this machine (once; later runs reuse it) and run it.
#   ./run.sh view [ARGS...]   set up, then open the viewer (default scene)
#   ./run.sh test             set up, then ruff check, ruff format --check, pytest
#   ./run.sh docs             set up, then build the documentation site into docs/_build/html
#   ./run.sh envstudio ARGS   set up, then any envstudio subcommand
set -euo pipefail
cd "$(dirname "$0")"

# binutils: objdump and objcopy, which PyInstaller needs for the bundle (tests/test_packaging_bundle.py);
# chromium: the headless browser that checks the atlas page (tests/test_atlas_gl.py)
DEBIAN_PACKAGES=(libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri xvfb xauth binutils chromium)

install_debian_packages() {
    command -v dpkg-query >/dev/null || return 0
    local missing=()
    for pkg in "${DEBIAN_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "ok installed" || missing+=("$pkg")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    if [ "$(id -u)" = 0 ]; then
        echo "run.sh: installing Debian packages: ${missing[*]}" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    else
        echo "run.sh: missing Debian packages (install them as root): ${missing[*]}" >&2
    fi
}

install_python_environment() {
    [ -x .venv/bin/python ] || python3 -m venv .venv
    local stamp
    stamp=".venv/.installed-$(cat requirements.lock pyproject.toml | sha1sum | cut -c1-12)"
    if [ ! -f "$stamp" ]; then
        echo "run.sh: installing Python packages into .venv" >&2
        .venv/bin/python -m pip install -q --upgrade pip
        .venv/bin/python -m pip install -q -r requirements.lock
        .venv/bin/python -m pip install -q --no-deps -e .
        rm -f .venv/.installed-*
        touch "$stamp"
    fi
}

# three.js (its KTX2Loader) and ktx-parse, the KTX2 readers nobody here wrote, for
# tests/test_prefilter_ktx2.py; into .node/ (ignored by git), pinned, once
NODE_PACKAGES=(three@0.187.0 ktx-parse@2.0.0)

install_node_packages() {
    if ! command -v npm >/dev/null && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        echo "run.sh: installing Debian packages: nodejs npm" >&2
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
    fi
    command -v npm >/dev/null || { echo "run.sh: npm not found: the KTX2 reader tests will fail" >&2; return 0; }
    local stamp=".node/.installed-$(echo "${NODE_PACKAGES[*]}" | sha1sum | cut -c1-12)"
    [ -f "$stamp" ] && return 0
    echo "run.sh: installing npm packages into .node: ${NODE_PACKAGES[*]}" >&2
    mkdir -p .node
    npm install --prefix .node --no-audit --no-fund --silent "${NODE_PACKAGES[@]}"
    rm -f .node/.installed-*
    touch "$stamp"
}

install_debian_packages
install_python_environment
install_node_packages

command="${1:-view}"
[ $# -gt 0 ] && shift
case "$command" in
    view) exec .venv/bin/envstudio view "$@" ;;
    test)
        .venv/bin/ruff check .
        .venv/bin/ruff format --check .
        .venv/bin/lint-imports
        OPENBLAS_NUM_THREADS=1 exec .venv/bin/pytest -q "$@" ;;
    docs)
        # a fresh build (-E): the technique pages and the gallery come from today's code; both
        # render through EGL, and without it docs/conf.py stops in one line
        .venv/bin/sphinx-build -b html -E -W --keep-going -q "$@" docs docs/_build/html
        echo "$PWD/docs/_build/html/index.html" ;;
    envstudio) exec .venv/bin/envstudio "$@" ;;
    *) echo "run.sh: unknown command '$command' (expected view, test, docs or envstudio)" >&2; exit 2 ;;
esac
