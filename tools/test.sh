#!/usr/bin/env bash
# The README's test command: set-up on a fresh machine, then every test.
set -euo pipefail
cd "$(dirname "$0")/.."
source tools/setup.sh
cargo build -p gait-cli
target/debug/gait models fetch blazepose
cargo test --workspace
