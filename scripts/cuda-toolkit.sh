# Sourced, not run: puts the CUDA 13.0 toolkit from PyPI on PATH for a `--features cuda` build,
# installing it into .cuda/venv the first time (nothing system-wide). `.ci/run` sources it to
# compile the feature; `scripts/gpu-check.sh` with CUDA_LIBRARIES=1 to link and run it too.
#
# The compiler alone: nvcc with its crt, nvvm, the CUDA headers and CCCL (candle's kernels
# include <nv/target>). CUDA_LIBRARIES=1 adds the libraries candle links (nvrtc, curand, cublas,
# cublasLt; libcuda is the driver's). Every package is pinned to 13.0: a newer nvvm or crt beside
# nvcc 13.0 writes PTX that its ptxas refuses ("Unsupported .version").
cuda_venv=${CUDA_VENV:-$PWD/.cuda/venv}
cuda_packages=("nvidia-cuda-nvcc==13.0.*" "nvidia-cuda-crt==13.0.*" "nvidia-nvvm==13.0.*"
  "nvidia-cuda-cccl==13.0.*" "nvidia-cuda-runtime==13.0.*")
if [ "${CUDA_LIBRARIES:-0}" = 1 ]; then
  cuda_packages+=("nvidia-cuda-nvrtc==13.0.*" "nvidia-cublas==13.0.*" "nvidia-curand==10.4.*")
fi
cuda_stamp="$cuda_venv/installed-$(printf '%s\n' "${cuda_packages[@]}" | sha256sum | cut -c1-16)"
if [ ! -e "$cuda_stamp" ]; then
  python3 -m venv "$cuda_venv"
  "$cuda_venv/bin/pip" install --quiet --disable-pip-version-check "${cuda_packages[@]}"
  touch "$cuda_stamp"
fi
cuda_root=$("$cuda_venv/bin/python" -c 'import os, nvidia; print(os.path.join(list(nvidia.__path__)[0], "cu13"))')
export PATH="$cuda_root/bin:$PATH" CUDA_PATH="$cuda_root" CUDA_ROOT="$cuda_root"
# candle's kernels are compiled for this compute capability (9.0: H100, H200) unless set.
export CUDA_COMPUTE_CAP="${CUDA_COMPUTE_CAP:-90}"
