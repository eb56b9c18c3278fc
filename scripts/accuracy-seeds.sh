#!/usr/bin/env bash
# The acceptance figures of docs/compensation.md: for each seed, a true robot from
# `robocal simulate`'s defaults, the default plan's data (config/cell.json) with the paper's noise
# (0.084 mm), a fit, and the accuracy over the reference work volume against the truth: the true
# robot commanded with the nominal joints and with the compensated joints. Prints one table row a
# seed and the worst case. Usage: scripts/accuracy-seeds.sh [SEEDS (default 10)]
# ROBOCAL_REALISM=typical (or a realism JSON file) gives the true robots what a real arm carries
# beside its geometry (robocal simulate --realism, docs/realism.md); the default is ideal.
# ROBOCAL_CELL: another cell file (e.g. with motion.approach_deg set).
# ROBOCAL_WHOLE_RANGE=N judges N joint vectors over the arm's whole range instead of the work
# volume (robocal accuracy --whole-range).
# ROBOCAL_SOLVE_ARGS: more options for robocal solve (e.g. --rigid: no compliance).
# ROBOCAL_PLAN_ARGS: more options for robocal plan (e.g. --time-budget-min 90).
# ROBOCAL_NOISE_MM: the bar's reading noise (default the paper's 0.084 mm).
# ROBOCAL_MODEL: another nominal model (e.g. with its chucks placed elsewhere on the table).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BUILD_DIR:-$root/build}
bin=$build/cli/robocal
seeds=${1:-10}
model=${ROBOCAL_MODEL:-$root/config/puma560.json}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# shellcheck disable=SC2086  # the options are words
"$bin" plan --model "$model" --cell "${ROBOCAL_CELL:-$root/config/cell.json}" ${ROBOCAL_PLAN_ARGS:-} \
  --out "$work/plan.json" >/dev/null
echo "| seed | samples | fit RMS (mm) | nominal joints RMS / p95 (mm) | compensated RMS / p95 / max (mm) | ratio | model's own RMS (mm) | predicted RMS (mm) | orientation nominal / compensated RMS (deg) |"
echo "|---|---|---|---|---|---|---|---|---|"
for seed in $(seq 1 "$seeds"); do
  "$bin" simulate --model "$model" --plan "$work/plan.json" --seed "$seed" \
    --noise-mm "${ROBOCAL_NOISE_MM:-0.084}" --realism "${ROBOCAL_REALISM:-ideal}" \
    --out "$work/s.csv" --truth-out "$work/truth.json" >/dev/null
  # --allow-partial: a fit the verdict refuses is still measured here (its problems in fit.json).
  # shellcheck disable=SC2086  # the options are words
  "$bin" solve --model "$model" "$work/s.csv" --out "$work/cal.json" --json --allow-partial \
    ${ROBOCAL_SOLVE_ARGS:-} \
    >"$work/fit.json" 2>/dev/null
  where=()
  [[ -n ${ROBOCAL_WHOLE_RANGE:-} ]] && where=(--whole-range "$ROBOCAL_WHOLE_RANGE")
  "$bin" accuracy --nominal "$model" --calibrated "$work/cal.json" --truth "$work/truth.json" \
    "${where[@]}" --json >"$work/acc.json"
  jq -r --argjson seed "$seed" --slurpfile fit "$work/fit.json" '
    def f(x): (x * 10000 | round) / 10000;
    def twist: if $fit[0].compliance then (if $fit[0].compliance.identified then " (twist kept)" else " (twist not kept)" end) else "" end;
    "| \($seed)\(twist) | \($fit[0].n) | \(f($fit[0].rms_mm)) | \(f(.nominal_commanded_position_error_mm.rms)) / \(f(.nominal_commanded_position_error_mm.p95)) | \(f(.compensated_commanded_position_error_mm.rms)) / \(f(.compensated_commanded_position_error_mm.p95)) / \(f(.compensated_commanded_position_error_mm.max)) | \((.nominal_commanded_position_error_mm.rms / .compensated_commanded_position_error_mm.rms * 10 | round) / 10) | \(f(.calibrated_model_position_error_mm.rms)) | \(f(.predicted_position_error_mm.rms)) | \(f(.nominal_commanded_orientation_error_deg.rms)) / \(f(.compensated_commanded_orientation_error_deg.rms)) |"' \
    "$work/acc.json"
done
