#!/usr/bin/env bash
# The Python package (issue 37): installs python/ into a fresh venv and runs its pytest
# tests. The package (a member of the workspace, python/Cargo.toml) is built into the
# workspace's target folder with the settings of the workspace's `test` profile (`--profile
# dev` with the test profile's opt-level; `--profile test` would make `cargo rustc` build a
# test harness), so that it reuses what `cargo test --workspace` compiled just before and
# compiles only pyo3, numpy and the module itself (python/README.md).
# Needs: python3 with venv and pip (PyPI reachable), cargo; ILLUME_BIN (the `illume`
# binary the CLI comparisons run; .ci/run sets it).
#
# `python.sh --venv DIR` only makes the virtual environment with the tools and packages
# the tests need (network-bound: .ci/run does it beside the test build); `python.sh` with
# ILLUME_PY_VENV=DIR then uses it instead of making its own.
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$PWD
make_venv() {
    python3 -m venv "$1"
    "$1/bin/python" -m pip install -q --disable-pip-version-check "maturin>=1.9,<2" \
        "numpy>=1.21" pytest matplotlib
}
if [ "${1:-}" = "--venv" ]; then
    make_venv "$2"
    exit 0
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
t0=$(date +%s)
venv="${ILLUME_PY_VENV:-}"
if [ -z "$venv" ]; then
    venv="$work/venv"
    make_venv "$venv"
fi
py="$venv/bin/python"
t1=$(date +%s)
PATH="$venv/bin:$PATH" MATURIN_PEP517_ARGS="--profile dev" CARGO_PROFILE_DEV_OPT_LEVEL=3 \
    "$py" -m pip install -q --disable-pip-version-check --no-build-isolation "$root/python"
t2=$(date +%s)
# From another folder, so that `import illume` is the installed package.
(cd "$work" && "$py" -m pytest -q -p no:cacheprovider "$root/python/tests")
t3=$(date +%s)
# The latency example (issue 37 goal 3) at a tiny size: it runs and writes its plot.
(cd "$work" && "$py" "$root/examples/python/latency.py" --frames 2 --warmup 1 --width 16 \
    --height 12 --spp 4 -o "$work/latency.png" >/dev/null)
test -s "$work/latency.png"
t4=$(date +%s)
[ -n "${ILLUME_PY_VENV:-}" ] && made="venv made beside the build" || made="venv + pip $((t1 - t0)) s"
echo "python: $made, package build $((t2 - t1)) s, pytest $((t3 - t2)) s, example $((t4 - t3)) s"
