#!/usr/bin/env bash
# The GPU backend's figures on a machine with a real GPU, in one run (issue 45): bench_gpu at 10k, 100k and 1M
# particles, one table. Built here (scripts/setup), then run there from a copy of the tree with the build carried.
#
# A machine lent with a GPU may have no Vulkan loader. Bring Debian's, once, in the repository root:
#   echo /.gl/ >>.git/info/exclude; mkdir -p .gl /tmp/amd64/partial
#   o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
#   apt-get $o update; (cd .gl && apt-get $o download libvulkan1)
# and run with the build and .gl carried:  bash bench/gpu_device.sh
# The table goes to stdout and to $OUT/gpu_device.txt when $OUT is set. A run stops itself after 8 minutes.
set -uo pipefail
cd "$(dirname "$0")/.."
if ! ldconfig -p | grep -q libvulkan.so.1; then
  for f in .gl/*.deb; do [[ -f $f ]] && dpkg -x "$f" /; done
  ldconfig
fi
# NVIDIA's driver file, where the machine keeps it outside the loader's search path.
for icd in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json \
           /etc/vulkan/icd.d/nvidia_icd.json; do
  [[ -z "${VK_DRIVER_FILES:-}" && -f $icd ]] && export VK_DRIVER_FILES=$icd
done
bin=build/release
out=${OUT:-/tmp}/gpu_device.txt
{
  echo "== nvidia-smi"; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 || true
  echo "== fluidform devices"; timeout 60 $bin/src/app/fluidform devices
  # Pick the first discrete or integrated GPU (never lavapipe).
  dev=$($bin/src/app/fluidform devices 2>/dev/null | awk '$0 ~ / (discrete|integrated) / {print $1; exit}')
  [[ -n "$dev" ]] || { echo "gpu_device: no discrete or integrated GPU among the Vulkan devices"; exit 1; }
  echo "== bench_gpu on device $dev"
  timeout 420 $bin/bench/bench_gpu --device "$dev" --particles 10000,100000,1000000 --repeats 9
} 2>&1 | tee "$out"
