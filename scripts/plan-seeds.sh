#!/usr/bin/env bash
# The acceptance figures of issue 13 (docs/performance.md, "Cell time"): grid plans of several
# densities and optimal plans of several budgets, each run on SEEDS simulated true robots
# (`robocal simulate` defaults, bar noise 0.084 mm), fitted, and judged over the reference work
# volume against the truth (the true robot commanded with the compensated joints). Prints one
# table row a plan (mean over the seeds of the work-volume RMS tool position error) and writes
# the figure of error against cell time to OUT_SVG.
# Usage: scripts/plan-seeds.sh [SEEDS (default 10)] [OUT_SVG (default docs/figures/cell-time.svg)]
# ROBOCAL_CELL: the cell file (default config/cell.json).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BUILD_DIR:-$root/build}
bin=$build/cli/robocal
seeds=${1:-10}
svg=${2:-$root/docs/figures/cell-time.svg}
model=$root/config/puma560.json
cell=${ROBOCAL_CELL:-$root/config/cell.json}
budgets=${ROBOCAL_PLAN_BUDGETS_MIN:-"18 27 36 54 90"}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# name kind plan-file
plans=()
grid() {  # name lat_step lon_step
  jq --argjson a "$2" --argjson o "$3" '.grid.latitude_step_deg = $a | .grid.longitude_step_deg = $o' \
    "$cell" >"$work/cell-$1.json"
  "$bin" plan --model "$model" --cell "$work/cell-$1.json" --out "$work/$1.json" --quiet \
    >"$work/$1.log"
  plans+=("$1 grid")
}
grid default 10 30
grid grid-20x30 20 30
grid grid-20x60 20 60
grid grid-10x15 10 15
for b in $budgets; do
  "$bin" plan --model "$model" --cell "$cell" --out "$work/opt-$b.json" --quiet \
    --time-budget-min "$b" >"$work/opt-$b.log"
  plans+=("opt-$b optimal")
done

echo "| plan | kind | shells | points | cell time (min) | predicted (mm) | true compensated RMS, mean of $seeds seeds (mm) | worst seed (mm) | vs default |"
echo "|---|---|---|---|---|---|---|---|---|"
: >"$work/rows.tsv"
default_err=""
for entry in "${plans[@]}"; do
  read -r name kind <<<"$entry"
  errs=()
  for seed in $(seq 1 "$seeds"); do
    "$bin" simulate --model "$model" --plan "$work/$name.json" --seed "$seed" --noise-mm 0.084 \
      --out "$work/s.csv" --truth-out "$work/truth.json" >/dev/null
    "$bin" solve --model "$model" "$work/s.csv" --out "$work/cal.json" >/dev/null
    "$bin" accuracy --nominal "$model" --calibrated "$work/cal.json" --truth "$work/truth.json" \
      --cell "$cell" --json >"$work/acc.json"
    errs+=("$(jq '.compensated_commanded_position_error_mm.rms' "$work/acc.json")")
  done
  mean=$(printf '%s\n' "${errs[@]}" | awk '{s+=$1} END {printf "%.4f", s/NR}')
  worst=$(printf '%s\n' "${errs[@]}" | sort -g | tail -1 | awk '{printf "%.4f", $1}')
  [[ -z $default_err ]] && default_err=$mean
  summary=$(jq -r '.summary | "\(.shells) \(.points) \(.cell_time_s)"' "$work/$name.json")
  read -r shells points cell_s <<<"$summary"
  predicted=$(sed -n 's/.*predicted RMS tool position error \([0-9.]*\) mm.*/\1/p' "$work/$name.log")
  cell_min=$(awk -v s="$cell_s" 'BEGIN {printf "%.1f", s / 60}')
  ratio=$(awk -v a="$mean" -v b="$default_err" 'BEGIN {printf "%.2f", a / b}')
  echo "| $name | $kind | $shells | $points | $cell_min | $predicted | $mean | $worst | $ratio |"
  printf '%s\t%s\t%s\t%s\n' "$name" "$kind" "$cell_min" "$mean" >>"$work/rows.tsv"
done
python3 "$root/scripts/cell_time_figure.py" "$work/rows.tsv" "$svg"
echo "figure: $svg"
