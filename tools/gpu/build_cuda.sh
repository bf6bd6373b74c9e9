#!/usr/bin/env bash
# Builds `gait` (and the regenerator benchmark example) with `--features cuda`
# in release, on a machine without a GPU or a CUDA toolkit: nvcc, the CUDA
# headers and the libraries to link against come from NVIDIA's PyPI wheels,
# installed once under $CARGO_TARGET_DIR/cuda-13.0 (about 1.2 GB).
#
# CUDA 13.0 on purpose: the GPU machines run driver 580 (CUDA 13.0) with
# torch 2.11+cu130, and the driver must be able to load the PTX that nvcc
# writes (a newer nvcc writes PTX that driver rejects).
#
#   tools/gpu/build_cuda.sh            # CUDA_COMPUTE_CAP=90 (H100, H200)
#   CUDA_COMPUTE_CAP=89 PYTHON=/path/to/python3 tools/gpu/build_cuda.sh
#
# Needs: a Python with pip (PYTHON, default python3), g++, cargo.
# Result: $CARGO_TARGET_DIR/release/gait and .../release/examples/regen_bench,
# linked against libcuda.so.1, libcublas(Lt).so.13, libcurand.so.10,
# libnvrtc.so.13 and libcudart.so.13, which must be on the GPU machine's
# library path at run time (tools/gpu/bench_regen.sh finds them).
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
target=${CARGO_TARGET_DIR:-$root/target}
cache=$target/cuda-13.0
python=${PYTHON:-python3}
cuda=$cache/site/nvidia/cu13
wheels=(
    nvidia-cuda-nvcc==13.0.88 nvidia-cuda-crt==13.0.88 nvidia-nvvm==13.0.88
    nvidia-cuda-runtime==13.0.96 nvidia-cuda-nvrtc==13.0.88 nvidia-cuda-cccl==13.0.85
    nvidia-cublas==13.0.2.14 nvidia-curand==10.4.0.35
)
stamp=$cache/wheels.txt
if [ ! -x "$cuda/bin/nvcc" ] || [ "$(cat "$stamp" 2>/dev/null)" != "${wheels[*]}" ]; then
    rm -rf "$cache/site"
    mkdir -p "$cache"
    # One pip call: `--target` replaces the shared nvidia/ folder on each call.
    "$python" -m pip install --quiet --no-deps --target "$cache/site" "${wheels[@]}"
    echo "${wheels[*]}" >"$stamp"
fi

# The wheels ship only versioned libraries; the linker looks for lib<name>.so.
for lib in cublas.so.13 cublasLt.so.13 cudart.so.13 nvrtc.so.13 curand.so.10; do
    ln -sf "lib$lib" "$cuda/lib/lib${lib%%.so.*}.so"
done
# libcuda comes with the driver, not with any wheel: link against a stub
# that has its soname and the driver API's symbols (cudarc's list), as the
# toolkit's own lib/stubs/libcuda.so does. The real one is loaded at run time.
stub=$cuda/lib/stubs/libcuda.so
if [ ! -f "$stub" ]; then
    mkdir -p "$(dirname "$stub")"
    sys=$(cargo metadata --format-version 1 --locked --features gait-cli/cuda --manifest-path "$root/Cargo.toml" |
        "$python" -c 'import json,sys; print(next(p["manifest_path"] for p in json.load(sys.stdin)["packages"] if p["name"]=="cudarc"))')
    sys=$(dirname "$sys")/src/driver/sys/mod.rs
    grep -o '^pub unsafe fn cu[A-Za-z0-9_]*' "$sys" | sed 's/^pub unsafe fn //' | sort -u |
        sed 's/.*/int &(void) { return 999; }/' >"$cache/libcuda_stub.c"
    gcc -shared -fPIC -Wl,-soname,libcuda.so.1 -o "$stub" "$cache/libcuda_stub.c"
fi

export CUDA_HOME=$cuda
export PATH=$cuda/bin:$PATH
export CUDA_COMPUTE_CAP=${CUDA_COMPUTE_CAP:-90}
export CARGO_TARGET_DIR=$target
nvcc --version | tail -2
cd "$root"
# One invocation, so both get the same features and candle's CUDA kernels (about an hour on
# 2 cores, most of it candle's quantized matmul kernels) are compiled once.
cargo build --release --locked -p gait-cli -p gait-diffuse --features gait-cli/cuda,gait-diffuse/cuda \
    --bin gait --example regen_bench
ls -l "$target/release/gait" "$target/release/examples/regen_bench"
