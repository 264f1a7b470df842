#!/usr/bin/env bash
# A/B of two fluidform builds on the formed shape, resumed from one checkpoint: the machine's speed drifts by up
# to 1.5x over minutes, so each round runs both builds for a short stretch (EXTRA frames) from the same formed
# state, back to back, and the ratio B/A of their median step times is taken per round. Medians of the ratios are
# steady to ~1 % where whole-run medians (bench/ab_steady.sh) drift by 10 %. The last frame's error rate is
# printed per build: a change that must not alter results shows the same value for both.
#   bench/ab_resume.sh BIN_A BIN_B [ROUNDS=6] [SCENE=examples/default_scene.json] [FORM=300] [EXTRA=40]
# The formed state is made once with BIN_A (FORM frames, --no-mesh) in a temporary folder.
set -euo pipefail
a=$1 b=$2 rounds=${3:-6} scene=${4:-examples/default_scene.json} form=${5:-300} extra=${6:-40}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-2}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$a" -q run "$scene" -o "$tmp/formed" --frames "$form" --no-mesh >/dev/null 2>&1
to=$((form + extra))
ratios=()
for r in $(seq "$rounds"); do
  line="round $r"
  meds=()
  for bin in "$a" "$b"; do
    rm -rf "$tmp/o" && cp -r "$tmp/formed" "$tmp/o"
    "$bin" -q run "$scene" -o "$tmp/o" --frames "$to" --resume --no-mesh >/dev/null 2>&1
    read -r med err < <(python3 - "$tmp/o/metrics.csv" "$form" <<'PY'
import csv, statistics as st, sys
rows = [x for x in csv.DictReader(open(sys.argv[1])) if int(x['frame']) > int(sys.argv[2])]
print(f"{1e3 * st.median(float(x['step_time_s']) for x in rows):.3f} {float(rows[-1]['error_rate_pct']):.4f}")
PY
)
    meds+=("$med")
    line="$line  $(basename "$bin") ${med} ms (E ${err} %)"
  done
  ratio=$(python3 -c "print(f'{${meds[1]} / ${meds[0]}:.3f}')")
  ratios+=("$ratio")
  echo "$line  B/A $ratio"
done
python3 -c "
import statistics as st
r = [float(x) for x in '${ratios[*]}'.split()]
print(f'median B/A {st.median(r):.3f} over {len(r)} rounds (min {min(r):.3f}, max {max(r):.3f})')"
