# Sourced by calibrate-sim.sh and soak.sh: the simulated cell both run.
#   start_sim_cell BUILD OUT MODEL CELL [more robocal-cellsim options]
# Starts robocal-cellsim with OUT/truth.json as the true robot (bar 150 mm, +/-2 mm of LVDT travel,
# 0.06 mm reading noise, motion 100 times faster; pty links and control socket in OUT), then
# robocald on a free port (and its console on another) with OUT/plan.json as its plan (settle and bar window 0.03 s). Appends
# both pids to the caller's `pids`, sets `daemon_pid`, `port` and `web_port`, exports ROBOCAL_TOKEN_FILE.
# Returns 1 (with robocald's log on stderr) when robocald does not listen.
# The controller speaks ROBOCAL_SIM_DIALECT (val2, the default; vplus; kawasaki-as: docs/drivers.md),
# cellsim and robocald alike.
start_sim_cell() {
  local build=$1 out=$2 model=$3 cell=$4
  local dialect=${ROBOCAL_SIM_DIALECT:-val2}
  shift 4
  echo "{\"val\": {\"dialect\": \"$dialect\"}}" >"$out/cellsim-drivers.json"
  "$build/sim/cellsim/robocal-cellsim" --config "$out/cellsim-drivers.json" \
    --model "$out/truth.json" --val-link "$out/val" \
    --bar-link "$out/bar" --control "$out/cellsim.sock" --time-scale 100 --bar-mode streamed \
    --stream-hz 100 --bar-mm 150 --range-mm 2.0 --noise-mm 0.06 --quantum-deg 0.005 "$@" \
    >"$out/cellsim.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do grep -q ready "$out/cellsim.log" && break; sleep 0.1; done
  cat >"$out/robocald.json" <<JSON
{
  "listen_address": "127.0.0.1", "port": 0, "web_port": 0, "data_dir": "$out/data",
  "model": "$model", "cell": "$cell", "plan": "$out/plan.json",
  "settle_s": 0.03, "bar_window_s": 0.03, "bar_soft_limit_mm": 1.0, "bar_hard_limit_mm": 1.6,
  "drivers": {
    "val": {"dialect": "$dialect", "serial": {"path": "$out/val"}, "poll_interval_s": 0.01},
    "bar": {"serial": {"path": "$out/bar"}, "mode": "streamed"}
  }
}
JSON
  "$build/daemon/robocald" --config "$out/robocald.json" >"$out/robocald.out" 2>"$out/robocald.log" &
  daemon_pid=$!
  pids+=("$daemon_pid")
  for _ in $(seq 100); do grep -q listening "$out/robocald.out" && break; sleep 0.1; done
  port=$(awk '/^listening/ {print $3}' "$out/robocald.out")
  web_port=$(awk '/^web/ {print $3}' "$out/robocald.out")
  if [[ -z $port ]]; then
    echo "robocald did not start:" >&2
    cat "$out/robocald.log" >&2
    return 1
  fi
  export ROBOCAL_TOKEN_FILE=$out/data/token
}
