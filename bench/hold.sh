#!/usr/bin/env bash
# Does a formed shape hold? Runs the bunny (scale 0.1) at N control particles for FRAMES frames and prints when it
# formed (≥ 99 % inside, ≤ 0.5 % splash for 1 s, as report.json's time_to_form_s), the least inside and most splash
# from then on, E over the first and the last second after forming (its drift), and the sub-steps and median step
# time of the formed frames. Not run by CI (the 100k bunny held to 10× its forming time is ~1 h on 2 cores).
#   bench/hold.sh BIN N FRAMES [OUT=mktemp]      e.g. bench/hold.sh build/release/src/app/fluidform 100000 600
set -euo pipefail
bin=$(realpath "$1") n=$2 frames=$3
out=${4:-$(mktemp -d)}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
cp "$root/examples/bunny.obj" "$out/"
printf '{"targets":[{"mesh":"bunny.obj","scale":0.1}],"sampling":{"auto_count":%d}}\n' "$n" >"$out/scene.json"
(cd "$out" && "$bin" -q run scene.json -o run --frames "$frames" --no-mesh >/dev/null)
python3 - "$out/run" "$n" <<'PY'
import csv, json, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1] + '/metrics.csv')))
rep = json.load(open(sys.argv[1] + '/report.json'))['totals']
t0 = rep['time_to_form_s']
if t0 is None:
    print(f"{sys.argv[2]} control particles: not formed in {rows[-1]['time_s']} s")
    sys.exit(0)
after = [r for r in rows if float(r['time_s']) >= t0 - 1e-6]  # time_s has 6 decimals
f = lambda r, k: float(r[k])
fps = round(1 / (f(rows[1], 'time_s') - f(rows[0], 'time_s')))
e_first = st.mean(f(r, 'error_rate_pct') for r in after[:fps])
e_last = st.mean(f(r, 'error_rate_pct') for r in after[-fps:])
print(f"{sys.argv[2]} control particles, {rows[-1]['particles']} fluid: formed at {t0:.2f} s, held to {rows[-1]['time_s']} s "
      f"({float(rows[-1]['time_s']) / max(t0, 1e-9):.1f}x the forming time)")
print(f"  after forming: least inside {100 * min(f(r, 'inside_fraction') for r in after):.2f} %, "
      f"most splash {100 * max(f(r, 'splash_fraction') for r in after):.2f} %")
print(f"  E first second {e_first:.4f} %, last second {e_last:.4f} %, drift {e_last - e_first:+.4f} pp")
print(f"  formed frames: {st.mean(int(r['substeps']) for r in after):.2f} sub-steps, "
      f"median step {1e3 * st.median(f(r, 'step_time_s') for r in after):.1f} ms")
PY
