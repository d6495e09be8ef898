#!/usr/bin/env bash
# Issue 25's GPU checks in one command, on a machine with an NVIDIA GPU and its driver:
#
#   bash scripts/gpu-check.sh [SIZES...]
#
# 1. the CUDA 13.0 toolkit from PyPI into .cuda/venv (scripts/cuda-toolkit.sh: compiler, headers
#    and the libraries candle links; libcuda is the driver's), nothing installed system-wide;
# 2. the `cuda` build (its own target folder, target/cuda);
# 3. the CPU-against-CUDA agreement test (the fused objective's values, gradients and the designs
#    tuned in 20 and 200 steps identical, bit for bit);
# 4. the timing table: `optimize` of 1, 8, 64, 256 and 4096 free designs, 8 goals x 4 starts x 200
#    steps, on the CPU and on CUDA (`examples/optimize_devices.rs`).
#
# Exit codes: 0 all ran and passed, 1 a check failed, 2 no NVIDIA GPU or driver here.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v nvidia-smi >/dev/null || ! nvidia-smi -L >/dev/null 2>&1; then
  echo "gpu-check: no NVIDIA GPU or driver on this machine (nvidia-smi -L fails): nothing to check" >&2
  exit 2
fi
nvidia-smi -L

capability=$(nvidia-smi --query-gpu=compute_cap --format=csv,noheader | head -1 | tr -d ' .')
export CUDA_COMPUTE_CAP="$capability" CUDA_LIBRARIES=1
# shellcheck source=scripts/cuda-toolkit.sh
source scripts/cuda-toolkit.sh
[ -n "$cuda_driver" ] || { echo "gpu-check: the driver's libcuda.so.1 is not in ldconfig's cache" >&2; exit 2; }
export CARGO_TARGET_DIR=target/cuda
echo "gpu-check: CUDA toolkit $(nvcc --version | sed -n 's/.*release \([0-9.]*\).*/\1/p'), compute capability $capability"

status=0
cargo build --release --locked --features cuda --example optimize_devices
cargo test --release --locked --features cuda --test optimize cuda_computes_what_the_cpu_computes -- --nocapture || status=1
"$CARGO_TARGET_DIR/release/examples/optimize_devices" "$@" || status=1
exit $status
