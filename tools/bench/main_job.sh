#!/usr/bin/env bash
# Issue 40: the README's main command against myogait 0.9.2's full pipeline
# (mediapipe 0.10.14, its legacy pose API) on the same video, interleaved rounds.
#   bash tools/bench/main_job.sh [--rounds N] [--gait PATH] [--input VIDEO]
#                                [--md FILE] [--json FILE]
# Every download (Debian packages, ONNX Runtime, the BlazePose wheel, myogait's
# wheels) is cached under target/, so a rerun is offline. See tools/bench/README.md.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
source tools/setup.sh

# The gait binary, as --gait names it (default: the README's target/debug/gait).
gait="target/debug/gait"
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  case "${args[$i]}" in
    --gait) gait="${args[$((i + 1))]:-}" ;;
    --gait=*) gait="${args[$i]#--gait=}" ;;
  esac
done
# The README command needs the BlazePose files; fetch them (untimed) only if
# missing, so a shared models folder is left as it is.
if [ ! -f "$GAIT_MODELS_DIR/blazepose/pose_landmark_full.tflite" ]; then
  "$gait" models fetch blazepose
fi

# myogait's virtual environment, rebuilt when the pins change. pip's cache in
# target/ keeps a CI rerun from downloading the wheels again.
venv="$root/target/bench/myogait-venv"
req="$root/tools/bench/myogait-requirements.txt"
export PIP_CACHE_DIR="$root/target/bench/pip-cache"
if ! cmp -s "$req" "$venv/installed-requirements.txt"; then
  echo "bench: installing myogait's environment into $venv" >&2
  rm -rf "$venv"
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check -r "$req"
  cp "$req" "$venv/installed-requirements.txt"
fi
# matplotlib builds its font list on first import; do it now, untimed, so the
# first measured myogait round does not pay a one-off cost the others skip.
MPLCONFIGDIR="$root/target/bench/mplconfig" "$venv/bin/python" -c 'import matplotlib.font_manager'
export MPLCONFIGDIR="$root/target/bench/mplconfig"

exec python3 tools/bench/main_job.py --myogait-python "$venv/bin/python" "$@"
