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
# candle's kernels are compiled by cudaforge on half the cores unless told: one nvcc at a time
# on a 2-core machine, some 15 minutes of candle-kernels' build there.
CUDAFORGE_THREADS="${CUDAFORGE_THREADS:-$(nproc)}"
export CUDAFORGE_THREADS

# CUDA_LIBRARIES=1: what the linker and the loader need for a `cuda` binary. The linker wants
# unversioned names (PyPI ships libcublas.so.13 and the like), linked under .cuda/lib. libcuda is
# the driver's: where there is one (ldconfig knows libcuda.so.1) it is linked there too; where
# there is none (a build machine without a GPU) the linker gets a stub of the driver's entry
# points (.cuda/stub, never on LD_LIBRARY_PATH, named libcuda.so.1 inside), so the binary links
# here and binds the real driver on the GPU machine it is copied to, as NVIDIA's own stubs do.
if [ "${CUDA_LIBRARIES:-0}" = 1 ]; then
  cuda_links=$PWD/.cuda/lib
  mkdir -p "$cuda_links"
  for lib in nvrtc curand cublas cublasLt cudart; do
    found=$(ls "$cuda_root/lib/lib$lib.so."* 2>/dev/null | grep -v alt | head -1 || true)
    [ -n "$found" ] || { echo "cuda-toolkit: lib$lib not in $cuda_root/lib" >&2; return 1; }
    ln -sf "$found" "$cuda_links/lib$lib.so"
  done
  # Read to the end (no early exit): under `set -o pipefail` a cut-off ldconfig would fail the line.
  cuda_driver=$( (ldconfig -p 2>/dev/null || true) | awk '/libcuda\.so\.1 .*x86-64/ && !found {print $NF; found = 1}')
  cuda_link_path=$cuda_links
  if [ -n "$cuda_driver" ]; then
    ln -sf "$cuda_driver" "$cuda_links/libcuda.so"
  else
    rm -f "$cuda_links/libcuda.so"
    cuda_stub=$PWD/.cuda/stub
    if [ ! -e "$cuda_stub/libcuda.so" ]; then
      mkdir -p "$cuda_stub"
      # Every driver entry point cudarc declares, as an empty function: the linker only checks names.
      cudarc_src=$(cargo metadata --format-version 1 --locked --features cuda 2>/dev/null \
        | python3 -c 'import json, sys; print(next(p["manifest_path"] for p in json.load(sys.stdin)["packages"] if p["name"] == "cudarc").rsplit("/", 1)[0])')
      grep -ho 'fn cu[A-Za-z0-9_]*(' "$cudarc_src/src/driver/sys/mod.rs" | sed 's/^fn \(.*\)($/int \1(void) { return 999; }/' \
        | sort -u >"$cuda_stub/libcuda.c"
      cc -shared -fPIC -Wl,-soname,libcuda.so.1 -o "$cuda_stub/libcuda.so" "$cuda_stub/libcuda.c"
    fi
    cuda_link_path=$cuda_links:$cuda_stub
  fi
  export LIBRARY_PATH="$cuda_link_path${LIBRARY_PATH:+:$LIBRARY_PATH}"
  export LD_LIBRARY_PATH="$cuda_links:$cuda_root/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
fi
