#!/usr/bin/env bash
# The drift every fit reports (docs/accuracy.md, "Drift"), over seeds 1 to 3 of each truth given:
# the default cell with a one-sided approach (0.02 deg), a revisit every 20 points and a reference
# pose every 5 minutes, simulated (ROBOCAL_NOISE_MM, default 0.084) and solved.
#   scripts/drift-seeds.sh ideal typical my-realism.json
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${ROBOCAL_BUILD_DIR:-$root/build}/cli/robocal
model=$root/config/puma560.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
jq '.motion.approach_deg = 0.02 | .motion.revisit_every = 20 | .motion.reference_every_min = 5' \
  "$root/config/cell.json" >"$work/cell.json"
"$bin" plan --model "$model" --cell "$work/cell.json" --out "$work/plan.json" >/dev/null
echo "| truth | seed | places | readings | span (min) | rate (mm/h) | 1 sigma (mm/h) | found |"
echo "|---|---|---|---|---|---|---|---|"
for realism in "$@"; do
  for seed in 1 2 3; do
    "$bin" simulate --model "$model" --plan "$work/plan.json" --seed "$seed" \
      --noise-mm "${ROBOCAL_NOISE_MM:-0.084}" --realism "$realism" --out "$work/s.csv" \
      --truth-out "$work/truth.json" >/dev/null
    # --allow-partial: a fit the verdict refuses still reports its drift.
    "$bin" solve --model "$model" "$work/s.csv" --out "$work/cal.json" --json --allow-partial \
      >"$work/fit.json" 2>/dev/null || true
    jq -r --arg truth "$(basename "$realism")" --argjson seed "$seed" '.adequacy.drift |
      def f(x): if x == null then "-" else (x * 1000 | round) / 1000 end;
      "| \($truth) | \($seed) | \(.places) | \(.readings) | \(f(.span_min)) | \(f(.rate_mm_per_h)) | \(f(.rate_sigma_mm_per_h)) | \(.found) |"' \
      "$work/fit.json"
  done
done
