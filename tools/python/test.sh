#!/usr/bin/env bash
# The Python package's tests (python/tests): the environment and wheel of setup.sh, then pytest
# against the `gait` command built by cargo ($GAIT_BIN, default target/debug/gait), with the models
# and ONNX Runtime where tools/setup.sh puts them unless the environment says otherwise.
# Usage: tools/python/test.sh [PYTEST ARGS...]
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/python/setup.sh >/dev/null
export GAIT_BIN="${GAIT_BIN:-target/debug/gait}"
export GAIT_MODELS_DIR="${GAIT_MODELS_DIR:-$PWD/target/models}"
ort="$PWD/target/gait-deps/onnxruntime/libonnxruntime.so.1.31.1"
if [ -z "${ORT_DYLIB_PATH:-}" ] && [ -f "$ort" ]; then
  export ORT_DYLIB_PATH="$ort"
fi
# The default pose model (a no-op when it is there); its output only when it fails.
if ! fetched="$("$GAIT_BIN" models fetch blazepose 2>&1)"; then
  echo "$fetched" >&2
  exit 1
fi
export PYTHONPATH="$PWD/examples/python${PYTHONPATH:+:$PYTHONPATH}"
target/python-venv/bin/python -m pytest -q -p no:cacheprovider python/tests "$@"
