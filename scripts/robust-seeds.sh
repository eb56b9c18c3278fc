#!/usr/bin/env bash
# Robust optimal plans (docs/cell-time.md, "Robust plans"): the default grid plan and optimal
# plans of one budget with several whole-range weights, each run on SEEDS simulated true robots
# (bar noise 0.084 mm), fitted, and judged against the truth in three places: the cell's work
# volume (shoulder right, as planned), the same box reached with the shoulder left, and the arm's
# whole range (200 joint vectors within its limits). Prints one table row a plan: the mean over
# the seeds of the compensated RMS tool position error in each place.
# Usage: scripts/robust-seeds.sh [SEEDS (default 10)] [BUDGET_MIN (default 32)]
# ROBOCAL_WEIGHTS: the whole-range weights to plan with (default "0 0.01 0.1"; robocal plan's
# default is 0.1). The box with the shoulder left is mostly outside the PUMA's joint limits: the
# table gives how many of its 200 poses were solved.
# ROBOCAL_REALISM: the true robots' realism (robocal simulate --realism; default ideal).
# ROBOCAL_CELL: the cell file (default config/cell.json).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BUILD_DIR:-$root/build}
bin=$build/cli/robocal
seeds=${1:-10}
budget=${2:-32}
model=$root/config/puma560.json
cell=${ROBOCAL_CELL:-$root/config/cell.json}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The reference work volume's box and orientations (docs/compensation.md), shoulder left.
awk 'BEGIN {
  srand(7); print "x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg,config"
  for (i = 0; i < 200; i++)
    printf "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,left-up-noflip\n", -250 + 400 * rand(),
      -250 + 500 * rand(), 150 + 250 * rand(), -30 + 60 * rand(), 120 + 30 * rand(),
      -30 + 60 * rand()
}' >"$work/left.csv"

plans=(default)
"$bin" plan --model "$model" --cell "$cell" --out "$work/default.json" --quiet >/dev/null
for w in ${ROBOCAL_WEIGHTS:-0 0.01 0.1}; do
  "$bin" plan --model "$model" --cell "$cell" --out "$work/opt-w$w.json" --quiet \
    --time-budget-min "$budget" --whole-range-weight "$w" >/dev/null
  plans+=("opt-w$w")
done

rms() { jq '.compensated_commanded_position_error_mm.rms' "$1"; }
echo "| plan | points | cell time (min) | predicted work volume / whole range (mm) | true work volume (mm) | true box, shoulder left (mm; poses solved) | true whole range (mm) | nominal, shoulder left (mm) |"
echo "|---|---|---|---|---|---|---|---|"
for name in "${plans[@]}"; do
  plan=$work/$name.json
  : >"$work/errs.tsv"
  for seed in $(seq 1 "$seeds"); do
    "$bin" simulate --model "$model" --plan "$plan" --seed "$seed" --noise-mm 0.084 \
      --realism "${ROBOCAL_REALISM:-ideal}" --out "$work/s.csv" --truth-out "$work/truth.json" \
      >/dev/null
    "$bin" solve --model "$model" "$work/s.csv" --out "$work/cal.json" --allow-partial \
      >/dev/null 2>&1
    acc() {
      "$bin" accuracy --calibrated "$work/cal.json" --truth "$work/truth.json" --json "$@" \
        2>/dev/null
    }
    acc >"$work/wv.json"
    acc --poses "$work/left.csv" >"$work/left.json" || true
    acc --whole-range 200 >"$work/whole.json"
    printf '%s\t%s\t%s\t%s\t%s\n' "$(rms "$work/wv.json")" "$(rms "$work/left.json")" \
      "$(rms "$work/whole.json")" \
      "$(jq '.nominal_commanded_position_error_mm.rms' "$work/left.json")" \
      "$(jq '.solved' "$work/left.json")" >>"$work/errs.tsv"
  done
  jq -r --arg name "$name" --slurpfile e <(awk '{print "[" $1 "," $2 "," $3 "," $4 "," $5 "]"}' "$work/errs.tsv") '
    def f(x): (x * 10000 | round) / 10000;
    def mean(i): ([$e[][i]] | add / length);
    "| \($name) | \(.summary.points) | \(f(.summary.cell_time_s / 60)) | \(f(.summary.predicted_work_volume_error_mm)) / \(f(.summary.predicted_whole_range_error_mm)) | \(f(mean(0))) | \(f(mean(1))); \(mean(4)) | \(f(mean(2))) | \(f(mean(3))) |"' \
    "$plan"
done
