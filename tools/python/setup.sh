#!/usr/bin/env bash
# The Python side of gait (issue 31): a virtual environment with the pinned packages of
# tools/python/requirements.txt (maturin, pytest, numpy, pandas, matplotlib, tqdm, nbclient,
# ipykernel, mediapipe), then the `gait` wheel built from python/ and installed into it.
#   target/python-venv   the environment (made with `python3 -m venv` when missing)
#   target/pip-cache     pip's download cache, inside the build folder that CI caches
#   target/wheels        the built wheel
# Idempotent: packages are installed again only when requirements.txt changed. Prints nothing
# but errors; its last line is the environment's path. GAIT_PY_SKIP_BUILD=1: no wheel.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
venv="$root/target/python-venv"
requirements="tools/python/requirements.txt"
export PIP_CACHE_DIR="$root/target/pip-cache"
export PIP_DISABLE_PIP_VERSION_CHECK=1

# A command's output only when it fails.
quiet() {
  local log
  log="$(mktemp)"
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2
    rm -f "$log"
    echo "tools/python/setup.sh: failed: $*" >&2
    return 1
  fi
  rm -f "$log"
}

if [ ! -x "$venv/bin/python" ]; then
  # Debian keeps venv's pip bootstrap in a package of its own.
  if ! python3 -c "import ensurepip" >/dev/null 2>&1; then
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    quiet $sudo_cmd apt-get update -qq
    quiet $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3-venv
  fi
  quiet python3 -m venv "$venv"
fi

stamp="$venv/.requirements.sha256"
want="$(sha256sum "$requirements" | cut -d' ' -f1)"
if [ "$(cat "$stamp" 2>/dev/null || true)" != "$want" ]; then
  quiet "$venv/bin/python" -m pip install -q -r "$requirements"
  echo "$want" >"$stamp"
fi

if [ -z "${GAIT_PY_SKIP_BUILD:-}" ]; then
  quiet "$venv/bin/maturin" build --profile dev -m python/Cargo.toml --out target/wheels -q
  wheel="$(ls -t target/wheels/gait-*.whl | head -n 1)"
  quiet "$venv/bin/python" -m pip install -q --force-reinstall --no-deps "$wheel"
fi
echo "$venv"
