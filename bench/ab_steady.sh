#!/usr/bin/env bash
# A/B of two fluidform builds on one scene, in alternating rounds (the machine's speed drifts, so the two are
# compared within each round): per build and round, the median step and control time over the frames after the
# shape formed (frames >= FROM), and the final error rate (identical when a change must not alter results).
#   bench/ab_steady.sh BIN_A BIN_B [ROUNDS=3] [SCENE=examples/default_scene.json] [FRAMES=240] [FROM=150]
set -euo pipefail
a=$1 b=$2 rounds=${3:-3} scene=${4:-examples/default_scene.json} frames=${5:-240} from=${6:-150}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for r in $(seq "$rounds"); do
  for bin in "$a" "$b"; do
    OMP_NUM_THREADS=${OMP_NUM_THREADS:-2} "$bin" -q run "$scene" -o "$out/run" --frames "$frames" --no-mesh >/dev/null 2>&1
    python3 - "$bin" "$out/run/metrics.csv" "$from" "$r" <<'PY'
import csv, statistics as st, sys
rows = [x for x in csv.DictReader(open(sys.argv[2])) if int(x['frame']) >= int(sys.argv[3])]
med = lambda k: 1e3 * st.median(float(x[k]) for x in rows)
print(f"round {sys.argv[4]}  {sys.argv[1]:40s} step {med('step_time_s'):7.2f} ms  control {med('control_time_s'):7.2f} ms  "
      f"E {float(rows[-1]['error_rate_pct']):.4f} %")
PY
  done
done
