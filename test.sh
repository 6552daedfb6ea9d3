#!/usr/bin/env bash
# The whole test suite on a fresh machine: installs what it lacks, then runs every test (unit,
# integration, property, doc and the off-screen render tests). CI runs exactly this script.
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

cargo test --locked --features render
