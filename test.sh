#!/usr/bin/env bash
# The whole test suite on a fresh machine: installs what it lacks, then runs every test (unit,
# integration, property, doc and the off-screen render tests, then the Python package's).
# CI runs exactly this script.
set -euo pipefail
cd "$(dirname "$0")"

# Off-screen rendering on a CPU-only machine: Mesa's software Vulkan driver (lavapipe).
if ! dpkg -s mesa-vulkan-drivers libvulkan1 >/dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers libvulkan1 \
        || { $sudo apt-get update && $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers libvulkan1; }
fi
cargo --version

start=$SECONDS
cargo test --locked --features render
echo "test.sh: the Rust tests (build and run) took $((SECONDS - start)) s" >&2
start=$SECONDS

# The Python package (python/, built by maturin with the locked dependencies) in a virtual
# environment of its own, with what its tests use (pytest, dask[distributed], pandas,
# pyarrow); its tests compare it with the CLI. Both are the test build's: the extension is
# built in the same profile and with the same features as the Rust tests above (the binding's
# Cargo.toml names the features the tests turn on), so it reuses their crates and only the
# binding and PyO3 are compiled here.
venv=target/python-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
MATURIN_PEP517_ARGS="--locked --profile dev --features lpc-damper/render" \
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "./python[test]"
LPC_BIN=target/debug/lpc "$venv/bin/python" -m pytest -q python/tests
echo "test.sh: the Python package (build and tests) took $((SECONDS - start)) s" >&2
