#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and runs a complete simulated
# calibration the way a cell would run it: robocal-cellsim plays the robot and the ball-bar on
# pseudo-terminals, robocald runs the two-set plan (nine shells, then nine with the 150 mm
# extension), and a simulated operator answers the connection prompts. Output in out/.
# The true robot is not its model: it carries a real arm's backlash, gravity compliance and
# warm-up and the LVDT's errors (ROBOCAL_REALISM, default typical: docs/realism.md; ideal for a
# robot that is exactly its model). As the shipped cells have it, every point is approached from
# below in each joint (motion.approach_deg, 0.02; ROBOCAL_APPROACH_DEG overrides, 0 for none) so
# that backlash is designed out (docs/accuracy.md), and every 20th point is measured again
# (motion.revisit_every; ROBOCAL_REVISIT_EVERY, 0 for none) so that the fit measures the bar's
# noise; here, beyond the cell, each shell's
# first point every 5 minutes of robot time (motion.reference_every_min
# ROBOCAL_REFERENCE_EVERY_MIN; 0 for none) so that it measures the drift over the run.
# ROBOCAL_PLAN_BUDGET_MIN=M runs an optimal plan of M minutes of cell time instead of the
# cell's grid (docs/cell-time.md). ROBOCAL_ROBOT=rx160 calibrates a Staubli RX160 under V+
# instead of the PUMA 560 under VAL II (docs/robots.md). ROBOCAL_MODEL: another nominal model of
# that robot (e.g. config/puma560-paper.json: the paper's compact fixture, docs/accuracy.md).
# ROBOCAL_SOLVE_ARGS: more options for the final fit (e.g. --rigid: no compliance).
# ROBOCAL_THROUGH_VIAS=true moves from point to point through the vias without stopping
# (motion.through_vias: a path program a point, blended by cellsim; docs/cell-time.md).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=sim-cell.sh
source "$root/scripts/sim-cell.sh"
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
build=${ROBOCAL_BUILD_DIR:-$root/build}
bin=$build/cli/robocal
out=${ROBOCAL_OUT:-$root/out}
# The arm (docs/robots.md): its nominal model config/<robot>.json and its controller's dialect.
robot=${ROBOCAL_ROBOT:-puma560}
case $robot in
  puma560) export ROBOCAL_SIM_DIALECT=val2 ;;  # Unimation VAL II
  rx160) export ROBOCAL_SIM_DIALECT=vplus ;;   # Staubli RX160 under V+ (CS7 controller)
  *)
    echo "ROBOCAL_ROBOT: no robot '$robot' (puma560, rx160)" >&2
    exit 2
    ;;
esac
model=${ROBOCAL_MODEL:-$root/config/$robot.json}
robot_cell=$root/config/cell.json
[[ -f $root/config/cell-$robot.json ]] && robot_cell=$root/config/cell-$robot.json
realism=${ROBOCAL_REALISM:-typical}
rm -rf "$out"
mkdir -p "$out"
cell=$out/cell.json
# The cell's approach and revisits unless set here; a reference pose every 5 minutes, so that the
# run's drift is reported (the shipped cell leaves it off: docs/accuracy.md, "Drift").
jq ".motion.approach_deg = ${ROBOCAL_APPROACH_DEG:-(.motion.approach_deg // 0)}
    | .motion.revisit_every = ${ROBOCAL_REVISIT_EVERY:-(.motion.revisit_every // 0)}
    | .motion.reference_every_min = ${ROBOCAL_REFERENCE_EVERY_MIN:-5}
    | .motion.through_vias = ${ROBOCAL_THROUGH_VIAS:-(.motion.through_vias // false)}" \
  "${ROBOCAL_CELL:-$robot_cell}" >"$cell"
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT

echo "== identifiability of the nine connections (paper Table I)"
"$bin" identify --model "$model" --connections all
echo
echo "== a perturbed true robot (the simulate defaults: balls 1-2 mm off the nominal), realism $realism"
"$bin" simulate --model "$model" --seed 7 --connections B1C1 --points-per-shell 1 \
  --realism "$realism" --out "$out/unused.csv" --truth-out "$out/truth.json" | tail -3
echo
echo "== the off-line plan"
budget=()
[[ -n ${ROBOCAL_PLAN_BUDGET_MIN:-} ]] && budget=(--time-budget-min "$ROBOCAL_PLAN_BUDGET_MIN")
"$bin" plan --model "$model" --cell "$cell" --out "$out/plan.json" "${budget[@]}" |
  grep -E "^(plan|identification|forecast|work volume|whole range|optimal|planned)"
echo
echo "== robocal-cellsim ($robot, $ROBOCAL_SIM_DIALECT, and the ball-bar on pseudo-terminals) and robocald"
start_sim_cell "$build" "$out" "$model" "$cell"
echo "robocald on 127.0.0.1:$port, its console on http://127.0.0.1:$web_port/; cellsim control $out/cellsim.sock"
echo
echo "== the run (the simulated operator answers each prompt)"
"$bin" watch --port "$port" --operator-cellsim "$out/cellsim.sock" --until done,paused,aborted,error \
  --timeout-s 1500 | grep -v "simulated operator" &
watch_pid=$!
sleep 0.5
"$bin" start --port "$port"
wait "$watch_pid"
echo
echo "== the result"
"$bin" result --port "$port" --json >"$out/result.json"
samples_file=$(grep -o '"samples_file":"[^"]*"' "$out/result.json" | cut -d'"' -f4)
run_dir=$(dirname "$samples_file")
sim_status=$("$bin" cellsim "$out/cellsim.sock" status)
field() { grep -o "$1=[^ ]*" <<<"$sim_status" | cut -d= -f2; }
echo "simulated bar: broken_events=$(field broken_events) (over-range events), largest deflection while moving $(field moving_peak_mm) mm"
echo "simulated robot: $(field moves) motions, $(field paths) of them path programs through vias (motion.through_vias)"
echo "re-centring moves: $(grep -c '"recentre"' "$run_dir/events.jsonl" || true), re-plans: $(grep -c '"replan"' "$run_dir/events.jsonl" || true)"
echo
echo "== the calibrated model against the simulated truth (all samples of the run, refitted)"
# shellcheck disable=SC2086  # the options are words
# (the samples record how each point was approached: the model records it, compensate repeats it)
"$bin" solve --model "$model" "$run_dir/samples.csv" --truth "$out/truth.json" \
  ${ROBOCAL_SOLVE_ARGS:-} --out "$out/calibrated.json" --report "$out/report"
echo
echo "== where the user works: the true robot commanded with nominal and with compensated joints"
"$bin" accuracy --nominal "$model" --calibrated "$out/calibrated.json" --truth "$out/truth.json" \
  --cell "$cell" --svg "$out/accuracy.svg"
echo
echo "== beyond it, over the arm's whole range (1,000 joint vectors within its limits): the same"
"$bin" accuracy --nominal "$model" --calibrated "$out/calibrated.json" --truth "$out/truth.json" \
  --whole-range 1000
echo
echo "== the verdict (robocald's last fit, as RESULT and the console give it)"
"$bin" result --port "$port"
echo
echo "Done. Run folder: $run_dir; calibrated model: $out/calibrated.json; report: $out/report/"
echo "Corrected joint targets from it: $bin compensate --model $out/calibrated.json --targets FILE --out FILE"
echo "robocal is not installed: call it as $bin, or put it on PATH for this shell with"
echo "  export PATH=\"$(dirname "$bin"):\$PATH\""
