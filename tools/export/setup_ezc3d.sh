#!/usr/bin/env bash
# Python environment with ezc3d, the reference C3D reader that gait-c3d's tests check the
# written files against (crates/gait-c3d/tests/ezc3d.rs runs this script itself).
#   - venv at target/gait-deps/venv-ezc3d (inside the build folder: nothing outside the repo is
#     touched, and `cargo clean` removes it)
#   - ezc3d==1.7.2: its Linux x86_64 wheel for CPython 3.11 (manylinux_2_28) is on PyPI
#   - numpy==2.2.6: ezc3d's Python API returns numpy arrays; the version the repo's other tools pin
# Prints the venv's python path on stdout; everything else goes to stderr. Idempotent: once the
# stamp file is there it only prints the path. A lock serialises concurrent callers (tests run in
# parallel). PYTHON selects the interpreter that creates the venv (default python3, needs 3.11).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
deps="$root/target/gait-deps"
venv="$deps/venv-ezc3d"
ezc3d_version="1.7.2"
numpy_version="2.2.6"
stamp="$venv/.gait-installed-ezc3d-$ezc3d_version-numpy-$numpy_version"

if [ ! -f "$stamp" ]; then
  mkdir -p "$deps"
  exec 9>"$deps/venv-ezc3d.lock"
  flock 9
  # Another caller may have finished the install while this one waited for the lock.
  if [ ! -f "$stamp" ]; then
    echo "setup_ezc3d: creating $venv (ezc3d==$ezc3d_version, numpy==$numpy_version)" >&2
    rm -rf "$venv"
    "${PYTHON:-python3}" -m venv "$venv"
    "$venv/bin/python" -m pip install -q --disable-pip-version-check --only-binary=:all: \
      "ezc3d==$ezc3d_version" "numpy==$numpy_version" >&2
    "$venv/bin/python" -c "import ezc3d" >&2
    touch "$stamp"
  fi
fi
echo "$venv/bin/python"
