#!/usr/bin/env bash
# The aarch64 (NEON) tile kernel's tests on an x86-64 machine: gait-diffuse's kernel tests
# (tile kernels against the naive product, the packed product, attention, feed-forward) built
# for aarch64-unknown-linux-gnu and run under qemu-aarch64 (user mode). On an aarch64 host
# the ordinary test run covers them and this script does nothing.
#
# Installs what it needs: the Rust target (rustup), Debian's cross gcc and qemu-user (apt).
# The cross build goes to target/aarch64-unknown-linux-gnu (about 0.5 GB).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
if [ "$(uname -m)" = aarch64 ]; then
    echo "test_neon: aarch64 host, the native tests run the NEON kernel" >&2
    exit 0
fi
if ! rustup target list --installed | grep -qx aarch64-unknown-linux-gnu; then
    rustup target add aarch64-unknown-linux-gnu >&2
fi
if ! command -v aarch64-linux-gnu-gcc > /dev/null || ! command -v qemu-aarch64 > /dev/null; then
    sudo_=; [ "$(id -u)" = 0 ] || sudo_=sudo
    $sudo_ apt-get install -y -q gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user > /dev/null 2>&1 \
        || { $sudo_ apt-get update -q > /dev/null && \
             $sudo_ apt-get install -y -q gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user > /dev/null; }
fi
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export CC_aarch64_unknown_linux_gnu=aarch64-linux-gnu-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu"
cd "$root"
out=$(cargo test --target aarch64-unknown-linux-gnu -p gait-diffuse --no-default-features --lib -- \
    sgemm attention feed_forward --nocapture 2>&1) || { echo "$out" >&2; exit 1; }
echo "$out" | grep -E 'tile kernels|test result' >&2
# The run must have reached the NEON kernel, not only the portable one.
echo "$out" | grep -q '"neon"' || { echo "test_neon: the NEON kernel was not selected" >&2; exit 1; }
