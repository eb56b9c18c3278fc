#!/usr/bin/env bash
# The console in a real browser (issue 15; docs/console.md): robocal-cellsim + robocald as the main
# job runs them, a short plan (two shells of 8 points), the run started from the command line, then
# headless Chromium drives the page (console_browser.py): the trace moves, a prompt appears,
# Confirm without the token is refused, with it the run goes on, the progress advances, a
# screenshot mid-run, Abort. /metrics is scraped and parsed by prometheus_client meanwhile.
#   tests/web/console_test.sh BUILD_DIR SCREENSHOT.png
# Exit 77 (ctest: skipped) with the reason only when Chromium, chromedriver or selenium are
# missing: scripts/setup.sh installs them.
set -uo pipefail
build=$1
shot=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
# Debian's python, where python3-selenium is (a python3 earlier in PATH may be another one).
py=/usr/bin/python3
[[ -x $py ]] || py=python3
missing=()
command -v chromium >/dev/null || missing+=(chromium)
command -v chromedriver >/dev/null || missing+=(chromium-driver)
"$py" -c 'import selenium' 2>/dev/null || missing+=(python3-selenium)
"$py" -c 'import prometheus_client' 2>/dev/null || missing+=(python3-prometheus-client)
command -v jq >/dev/null || missing+=(jq)
if ((${#missing[@]})); then
  echo "SKIPPED: the browser test needs ${missing[*]} (scripts/setup.sh installs them)"
  exit 77
fi
mkdir -p "$(dirname "$shot")"
# shellcheck source=../../scripts/sim-cell.sh
source "$root/scripts/sim-cell.sh"
out=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$out"
}
trap cleanup EXIT
bin=$build/cli/robocal
model=$root/config/puma560-paper.json
cell=$root/config/cell.json
"$bin" simulate --model "$model" --seed 7 --connections B1C1 --points-per-shell 1 \
  --out "$out/unused.csv" --truth-out "$out/truth.json" >/dev/null || exit 1
"$bin" plan --model "$model" --cell "$cell" --out "$out/plan-full.json" --quiet >/dev/null || exit 1
# The first two shells up to their 8th point (a prefix of a safe path is safe).
jq '.shells |= (.[:2] | map(.steps |= (reduce .[] as $st ({n: 0, out: []};
      if .n < 8 then .out += [$st] | .n += (if $st.kind == "point" then 1 else 0 end) else . end)
      | .out)))' "$out/plan-full.json" >"$out/plan.json" || exit 1
start_sim_cell "$build" "$out" "$model" "$cell" --seed 3 || exit 1
[[ -n $web_port ]] || { echo "robocald printed no web port"; cat "$out/robocald.out"; exit 1; }
"$bin" start --port "$port" >"$out/start.log" 2>&1 || { cat "$out/start.log"; exit 1; }
"$py" "$root/tests/web/console_browser.py" --web-port "$web_port" --tcp-port "$port" \
  --token-file "$out/data/token" --cellsim "$out/cellsim.sock" --robocal "$bin" \
  --screenshot "$shot"
status=$?
if ((status != 0)); then
  echo "--- robocald log (tail)"
  tail -30 "$out/robocald.log"
fi
exit $status
