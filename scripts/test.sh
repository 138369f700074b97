#!/usr/bin/env bash
# The whole test suite, against real Blender: installs what is missing, then runs cargo test.
#   Blender 3.4 — Debian's `blender` package (a real binary)
#   Blender 4.5 LTS and 5.0 — PyPI's `bpy` (Blender as a Python module, CPython 3.11)
#   Chromium — Debian's `chromium`, to load and screenshot the HTML report
#   Mesa's software OpenGL (`libegl1`, `libgl1-mesa-dri`) — EEVEE renders headless with it
#   ruff — PyPI's, to lint the Blender-side Python and the bundled scripts (tests/python_lint.rs)
# Idempotent: a second run reuses what the first installed.
set -euo pipefail
cd "$(dirname "$0")/.."

cache="${GLOFFUSE_TEST_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/gloffuse/test-blenders}"
mkdir -p "$cache"

# Debian's blender (3.4), Mesa for EEVEE and, for the report page's browser test, chromium.
missing=""
command -v blender >/dev/null 2>&1 || missing="$missing blender"
[ -x /usr/bin/chromium ] || missing="$missing chromium"
for package in libegl1 libgl1-mesa-dri; do
    dpkg -s "$package" >/dev/null 2>&1 || missing="$missing $package"
done
if [ -n "$missing" ]; then
    echo "== installing Debian's$missing"
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $missing >/dev/null
fi

python="$(command -v python3.11 || command -v python3)"
provision_bpy() { # name, pip requirement
    local dir="$cache/$1"
    if [ ! -x "$dir/bin/python" ] || ! "$dir/bin/python" -c "import bpy" >/dev/null 2>&1; then
        echo "== installing $2 into $dir"
        rm -rf "$dir.partial" "$dir"
        "$python" -m venv "$dir.partial"
        "$dir.partial/bin/pip" install --quiet --progress-bar off "$2"
        mv "$dir.partial" "$dir"
    fi
}
provision_ruff() { # pip requirement
    local dir="$cache/ruff"
    if [ ! -x "$dir/bin/ruff" ] || ! "$dir/bin/ruff" --version >/dev/null 2>&1; then
        echo "== installing $1 into $dir"
        rm -rf "$dir.partial" "$dir"
        "$python" -m venv "$dir.partial"
        "$dir.partial/bin/pip" install --quiet --progress-bar off "$1"
        mv "$dir.partial" "$dir"
    fi
}
provision_bpy bpy-4.5 'bpy>=4.5,<4.6' & bpy45=$!
provision_bpy bpy-5.0 'bpy>=5.0,<5.1' & bpy50=$!
provision_ruff 'ruff>=0.17,<0.18' & ruff=$!
wait "$bpy45"; wait "$bpy50"; wait "$ruff"

export GLOFFUSE_TEST_BLENDER_34="$(command -v blender)"
export GLOFFUSE_TEST_BPY_45="$cache/bpy-4.5/bin/python"
export GLOFFUSE_TEST_BPY_50="$cache/bpy-5.0/bin/python"
export GLOFFUSE_TEST_RUFF="$cache/ruff/bin/ruff"
"$GLOFFUSE_TEST_BLENDER_34" -b --factory-startup -noaudio --version 2>/dev/null | head -1
"$GLOFFUSE_TEST_BPY_45" -c "import bpy; print('bpy', bpy.app.version_string)"
"$GLOFFUSE_TEST_BPY_50" -c "import bpy; print('bpy', bpy.app.version_string)"
"$GLOFFUSE_TEST_RUFF" --version

cargo test --locked "$@"
