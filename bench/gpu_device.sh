#!/usr/bin/env bash
# The GPU backend's figures on a machine with a real GPU, in one run (issue 45): bench_gpu at 10k, 100k and 1M
# particles (per pass, beside the CPU sub-step), then the default bunny forming on the GPU at 100k and 1M particles
# (`fluidform run --device gpu`, the adaptive controller, surface tension and drag included, particles written every
# frame), one table each. Built here (scripts/setup), then run there from a copy of the tree with the build carried.
#
# A machine lent with a GPU may have no Vulkan loader. Bring Debian's, once, in the repository root:
#   echo /.gl/ >>.git/info/exclude; mkdir -p .gl /tmp/amd64/partial
#   o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
#   apt-get $o update; (cd .gl && apt-get $o download libvulkan1)
# and run with the build and .gl carried:  bash bench/gpu_device.sh
# The output goes to stdout and to $OUT/gpu_device.txt when $OUT is set. It stops itself within 8 minutes.
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
exe=$bin/src/app/fluidform
out=${OUT:-/tmp}/gpu_device.txt
work=$(mktemp -d)
{
  echo "== nvidia-smi"; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 || true
  echo "== fluidform devices"; timeout 60 $exe devices
  # The first discrete or integrated GPU (never lavapipe).
  dev=$($exe devices 2>/dev/null | awk '$0 ~ / (discrete|integrated) / {print $1; exit}')
  [[ -n "$dev" ]] || { echo "gpu_device: no discrete or integrated GPU among the Vulkan devices"; exit 1; }
  echo "== bench_gpu on device $dev"
  timeout 200 $bin/bench/bench_gpu --device "$dev" --particles 10000,100000,1000000 --repeats 9
  # The default bunny at 100k and 1M particles on the GPU ('gpu' takes the first discrete GPU, as above).
  for n in 100000 1000000; do
    frames=$((n > 100000 ? 60 : 300))
    printf '{"targets": [{"mesh": "%s", "scale": 0.1}], "sampling": {"auto_count": %d, "max_auto_count": %d}, "output": {"frames": %d}}\n' \
      "$PWD/examples/bunny.obj" "$n" "$n" "$frames" > "$work/bunny_$n.json"
    echo "== the bunny at $n particles, $frames frames, --device gpu"
    timeout 120 $exe -q run "$work/bunny_$n.json" -o "$work/out_$n" --device gpu --no-mesh --max-memory 100000
    echo "exit $?"
    python3 - "$work/out_$n/report.json" <<'PY' || true
import json, sys
r = json.load(open(sys.argv[1]))
t = r.get("totals", {})
print(f"device {r.get('device')}: {t.get('particles')} particles, {t.get('mean_step_time_s', float('nan')) * 1e3:.2f} ms a frame "
      f"(simulation, particles brought back every frame), E {t.get('error_rate_pct')} %, inside {t.get('inside_fraction')}, "
      f"splash {t.get('splash_fraction')}")
PY
  done
} 2>&1 | tee "$out"
rm -rf "$work"
