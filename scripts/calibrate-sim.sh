#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and runs a simulated calibration.
# Output goes to out/ (or $ROBOCAL_OUT).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
bin=${ROBOCAL_BUILD_DIR:-$root/build}/cli/robocal
out=${ROBOCAL_OUT:-$root/out}
mkdir -p "$out"
model=$root/config/puma560.json

echo "== identifiability of the nine connections (paper Table I)"
"$bin" identify --model "$model" --connections all
echo
echo "== simulated measurements: nine shells with a perturbed true robot"
"$bin" simulate --model "$model" --seed 7 --noise-mm 0.084 --connections all --extension-mm 0 \
  --points-per-shell 90 --out "$out/samples.csv" --truth-out "$out/truth.json"
echo
echo "== validation shells with the 150 mm extension bar, same true robot"
"$bin" simulate --model "$model" --truth "$out/truth.json" --seed 8 --noise-mm 0.084 \
  --connections all --extension-mm 150 --points-per-shell 90 --first-shell 10 \
  --out "$out/validation.csv"
echo
echo "== identification: Levenberg-Marquardt from the nominal model, validated on the extension set"
"$bin" solve --model "$model" "$out/samples.csv" --out "$out/calibrated.json" \
  --validate "$out/validation.csv" --truth "$out/truth.json" --report "$out/report"
echo
echo "Done: calibrated model $out/calibrated.json, report $out/report/ (report.json and SVG figures)."
