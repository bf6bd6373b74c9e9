#!/usr/bin/env bash
# Set-up shared by the README's two commands (tools/sample.sh, tools/test.sh).
# Installs what a fresh machine lacks and caches every download inside the
# build folder (target/), so later runs are offline and quick.
#   - Debian packages: ffmpeg (video decoding), fonts-dejavu-core (plots),
#     chromium (report test), poppler-utils (pdftotext/pdfinfo: the PDF test)
#   - ONNX Runtime shared library from the PyPI wheel onnxruntime==1.31.1
#     (the ort backend loads it at run time)
# Source it: it exports ORT_DYLIB_PATH and GAIT_MODELS_DIR.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
deps="$root/target/gait-deps"
mkdir -p "$deps"

need_apt=()
command -v ffmpeg >/dev/null || need_apt+=(ffmpeg)
[ -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || need_apt+=(fonts-dejavu-core)
command -v chromium >/dev/null || need_apt+=(chromium)
command -v pdftotext >/dev/null || need_apt+=(poppler-utils)
# libjpeg-turbo's bundled build (the turbojpeg crate, gait-pipeline's JPEG reader): cmake, and
# nasm for its SIMD code (what OpenCV and Pillow run).
command -v cmake >/dev/null || need_apt+=(cmake)
command -v nasm >/dev/null || need_apt+=(nasm)
if [ ${#need_apt[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${need_apt[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
fi

ort_lib="$deps/onnxruntime/libonnxruntime.so.1.31.1"
if [ ! -f "$ort_lib" ]; then
  echo "setup: fetching ONNX Runtime 1.31.1 (PyPI wheel onnxruntime)" >&2
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.11 \
    --platform manylinux_2_27_x86_64 --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 \
    onnxruntime==1.31.1 -d "$deps/wheels"
  mkdir -p "$deps/onnxruntime"
  python3 - "$deps/wheels" "$deps/onnxruntime" <<'PY'
import glob, sys, zipfile
whl = glob.glob(sys.argv[1] + "/onnxruntime-1.31.1-*.whl")[0]
with zipfile.ZipFile(whl) as z:
    data = z.read("onnxruntime/capi/libonnxruntime.so.1.31.1")
open(sys.argv[2] + "/libonnxruntime.so.1.31.1", "wb").write(data)
PY
fi
export ORT_DYLIB_PATH="$ort_lib"
export GAIT_MODELS_DIR="${GAIT_MODELS_DIR:-$root/target/models}"
