#!/usr/bin/env bash
# The model-adequacy test's acceptance (docs/accuracy.md): the default plan (config/cell.json, or
# ROBOCAL_CELL), the paper's noise, true robots of `robocal simulate` seeds 1..N with the realism
# given, fitted; counts the fits whose adequacy test found a pattern, and prints each fit's summary.
#   scripts/adequacy-seeds.sh SEEDS REALISM     (REALISM: ideal, typical or a JSON file)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${ROBOCAL_BUILD_DIR:-$root/build}/cli/robocal
seeds=${1:-5}
realism=${2:-ideal}
model=$root/config/puma560.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin" plan --model "$model" --cell "${ROBOCAL_CELL:-$root/config/cell.json}" --out "$work/plan.json" >/dev/null
fired=0
for seed in $(seq 1 "$seeds"); do
  "$bin" simulate --model "$model" --plan "$work/plan.json" --seed "$seed" --noise-mm 0.084 \
    --realism "$realism" --out "$work/s.csv" >/dev/null
  "$bin" solve --model "$model" "$work/s.csv" --json --allow-partial >"$work/fit.json" 2>/dev/null || true
  ok=$(jq -r '.adequacy.ok' "$work/fit.json")
  [[ $ok == true ]] || fired=$((fired + 1))
  echo "seed $seed: $(jq -r '.adequacy.summary' "$work/fit.json")"
done
echo "adequacy-seeds ($realism): a pattern found in $fired of $seeds fits"
