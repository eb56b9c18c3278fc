#!/usr/bin/env bash
# Soak (issue 7, item 5; docs/reliability.md): the main job's two-set plan run again and again
# through robocald against robocal-cellsim at --time-scale 100, for MINUTES of wall time, with
# random serial faults injected through cellsim's control socket (the run resumed after each
# fault pause, as an operator would) and client churn (watchers that read and leave, watchers that
# never read, one-shot status requests). Samples robocald's RSS and open fds each second. At the
# end, PASS/FAIL for: every plan point of every completed run recorded exactly once in its
# samples.csv (and no run with a duplicate); RSS flat; fds back to their baseline; every injected
# fault visible in the event log. Exits 1 on any FAIL.
#
#   scripts/soak.sh [MINUTES]              (default 30; installs and builds what it needs first)
#
# Environment: ROBOCAL_BUILD_DIR (default build/), ROBOCAL_SOAK_OUT (default out/soak/),
# ROBOCAL_SOAK_SEED (random seed), ROBOCAL_SOAK_STEPS_PER_SHELL (each shell up to its Nth data
# point: a shorter plan, for a short soak), ROBOCAL_SOAK_FAULT_EVERY_S (mean seconds between faults
# [30]), ROBOCAL_SOAK_RSS_GROWTH_PCT (allowed growth of the mean RSS, last third against first
# third after warm-up [10]).
set -uo pipefail
minutes=${1:-30}
root=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=sim-cell.sh
source "$root/scripts/sim-cell.sh"
build=${ROBOCAL_BUILD_DIR:-$root/build}
bin=$build/cli/robocal
out=${ROBOCAL_SOAK_OUT:-$root/out/soak}
seed=${ROBOCAL_SOAK_SEED:-$((($$ + $(date +%s)) % 32768))}
steps_per_shell=${ROBOCAL_SOAK_STEPS_PER_SHELL:-0}
fault_every_s=${ROBOCAL_SOAK_FAULT_EVERY_S:-30}
rss_growth_pct=${ROBOCAL_SOAK_RSS_GROWTH_PCT:-10}
model=$root/config/puma560.json
cell=${ROBOCAL_CELL:-$root/config/cell.json}
RANDOM=$seed
"$root/scripts/setup.sh" || exit 2
ROBOCAL_BUILD_DIR=$build "$root/scripts/build.sh" || exit 2
for f in "$bin" "$build/daemon/robocald" "$build/sim/cellsim/robocal-cellsim"; do
  [[ -x $f ]] || { echo "soak: $f missing (build robocald, robocal-cellsim, robocal)" >&2; exit 2; }
done
command -v jq >/dev/null || { echo "soak: needs jq" >&2; exit 2; }

rm -rf "$out"
mkdir -p "$out"
pids=()
cleanup() {
  touch "$out/stop"
  [[ -f $out/operator.pid ]] && kill "$(cat "$out/operator.pid")" 2>/dev/null
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
}
trap cleanup EXIT
now_iso() { date -u +%Y-%m-%dT%H:%M:%S.%3NZ; }
log() { echo "[$(date +%H:%M:%S)] $*" | tee -a "$out/soak.log"; }
log "soak: $minutes min, seed $seed, output $out"

"$bin" simulate --model "$model" --seed 7 --connections B1C1 --points-per-shell 1 \
  --out "$out/unused.csv" --truth-out "$out/truth.json" >/dev/null
"$bin" plan --model "$model" --cell "$cell" --out "$out/plan-full.json" --quiet >/dev/null
if ((steps_per_shell > 0)); then
  # Each shell up to its Kth data point (a prefix of a safe path is safe).
  jq --argjson k "$steps_per_shell" '.shells |= map(.steps |= (reduce .[] as $st ({n: 0, out: []};
      if .n < $k then .out += [$st] | .n += (if $st.kind == "point" then 1 else 0 end) else . end)
      | .out))' "$out/plan-full.json" >"$out/plan.json"
else
  cp "$out/plan-full.json" "$out/plan.json"
fi
plan_points=$(jq '[.shells[].steps[] | select(.kind == "point")] | length' "$out/plan.json")
log "plan: $(jq '.shells | length' "$out/plan.json") shells, $plan_points points"

start_sim_cell "$build" "$out" "$model" "$cell" --seed "$seed" || exit 2
sock=$out/cellsim.sock
log "robocald pid $daemon_pid on 127.0.0.1:$port"

rc() { "$bin" "$@" --port "$port"; }
state() { rc status --json 2>/dev/null | jq -r '.state // "?"' 2>/dev/null || echo "?"; }
cellsim() { "$bin" cellsim "$sock" "$@"; }

# The resource sampler: time, RSS (kB), open fds, once a second.
(
  while [[ ! -e $out/stop ]] && kill -0 "$daemon_pid" 2>/dev/null; do
    rss_kb=$(awk '/^VmRSS/ {print $2}' "/proc/$daemon_pid/status" 2>/dev/null)
    fds=$(ls "/proc/$daemon_pid/fd" 2>/dev/null | wc -l)
    echo "$(date +%s) ${rss_kb:-0} $fds"
    sleep 1
  done
) >"$out/resources.txt" &
pids+=($!)

# The operator: answers every prompt (restarted when it gives up).
(
  while [[ ! -e $out/stop ]]; do
    "$bin" watch --port "$port" --operator-cellsim "$sock" >>"$out/operator.log" 2>&1 &
    echo $! >"$out/operator.pid"
    wait $!
    sleep 1
  done
) &
pids+=($!)
sleep 0.5

start_run() {
  if rc start >>"$out/soak.log" 2>&1; then
    runs_started=$((runs_started + 1))
    log "run $runs_started started"
  fi
}

# Fds with the devices connected and only the operator watching: the baseline the end returns to.
runs_started=0
start_run
for _ in $(seq 300); do [[ $(state) == measuring ]] && break; sleep 0.2; done
sleep 2
fd_baseline=$(ls "/proc/$daemon_pid/fd" | wc -l)
log "fd baseline (devices connected, one watcher): $fd_baseline"

# Client churn: readers that leave, readers that never read, one-shot requests, junk lines.
(
  n=0
  while [[ ! -e $out/stop ]]; do
    n=$((n + 1))
    case $((RANDOM % 4)) in
      0) timeout $((1 + RANDOM % 6)) "$bin" watch --port "$port" --json >/dev/null 2>&1 & ;;
      1)
        (
          exec 3<>"/dev/tcp/127.0.0.1/$port" || exit 0
          printf '{"cmd":"watch","enable":true}\n' >&3
          sleep $((5 + RANDOM % 20))
          exec 3>&-
        ) 2>/dev/null &
        ;;
      2) "$bin" status --port "$port" >/dev/null 2>&1 & ;;
      3)
        (
          exec 3<>"/dev/tcp/127.0.0.1/$port" || exit 0
          printf 'not json\n{"cmd":"nope"}\n{"cmd":"status"' >&3
          sleep 0.$((RANDOM % 10))
          exec 3>&-
        ) 2>/dev/null &
        ;;
    esac
    echo $n >"$out/churn.count"
    sleep 0.$((2 + RANDOM % 8))
  done
  wait
) &
churn_pid=$!
pids+=("$churn_pid")

# The faults, one at a time, while a data point is being measured.
kinds=(bar_garbage bar_drop val_garbage val_drop val_stall bar_stall val_disconnect
  bar_disconnect val_error bar_noprobe)
inject() {
  case $1 in
    bar_garbage) cellsim fault garbage ;;
    bar_drop) cellsim fault drop ;;
    val_garbage) cellsim fault garbage val ;;
    val_drop) cellsim fault drop val ;;
    val_stall) cellsim fault stall val 3 ;;
    bar_stall) cellsim fault stall bar 3 ;;
    val_disconnect) cellsim fault disconnect val "1.$((RANDOM % 10))" ;;
    bar_disconnect) cellsim fault disconnect bar "1.$((RANDOM % 10))" ;;
    val_error) cellsim fault error Soak injected error ;;
    bar_noprobe) cellsim fault noprobe ;;
  esac
}
: >"$out/faults.tsv"
deadline=$(($(date +%s) + minutes * 60))
next_fault=$(($(date +%s) + 5 + RANDOM % (2 * fault_every_s)))
noprobe_on=0
resumes=0
since_prompt=0
completed=()
last_state=""
while (($(date +%s) < deadline)); do
  s=$(state)
  [[ $s != awaiting_confirm ]] && since_prompt=0
  [[ $s != "$last_state" ]] && echo "$(now_iso) $s" >>"$out/states.txt"
  last_state=$s
  case $s in
    done)
      id=$(rc status --json | jq -r .run)
      [[ " ${completed[*]} " == *" $id "* ]] || { completed+=("$id"); log "run $id done"; }
      start_run
      ;;
    paused | interrupted)
      if ((noprobe_on)); then
        cellsim fault noprobe off >/dev/null
        noprobe_on=0
      fi
      sleep 2 # a disconnected port comes back within 2 s
      if rc resume >>"$out/soak.log" 2>&1; then resumes=$((resumes + 1)); fi
      ;;
    aborted | error)
      log "state $s: $(rc status --json | jq -r .reason)"
      start_run
      ;;
    awaiting_confirm)
      # An operator that gave up (and was restarted) never saw the pending prompt: pause and
      # resume, which prompts again.
      if ((since_prompt == 0)); then
        since_prompt=$(date +%s)
      elif (($(date +%s) - since_prompt > 30)); then
        log "prompt unanswered for 30 s: pause and resume"
        rc pause --reason "soak: prompt unanswered" >>"$out/soak.log" 2>&1
        since_prompt=0
      fi
      ;;
    measuring)
      # None in the last 15 s: each fault gets the time to show before the run is stopped.
      if (($(date +%s) >= next_fault && $(date +%s) < deadline - 15)); then
        kind=${kinds[RANDOM % ${#kinds[@]}]}
        t=$(now_iso)
        if inject "$kind" | grep -q '^ok'; then
          printf '%s\t%s\n' "$t" "$kind" >>"$out/faults.tsv"
          [[ $kind == bar_noprobe ]] && noprobe_on=1
        fi
        next_fault=$(($(date +%s) + 5 + RANDOM % (2 * fault_every_s - 5)))
      fi
      ;;
  esac
  sleep 0.3
done

log "time is up: stopping the run and the clients"
if [[ $(state) != "done" ]]; then rc abort --reason "soak time is up" >>"$out/soak.log" 2>&1; fi
cellsim fault noprobe off >/dev/null
touch "$out/stop"
wait "$churn_pid" 2>/dev/null # the churn ends with its last clients (25 s at most)
sleep 3
fd_end=$(ls "/proc/$daemon_pid/fd" | wc -l)
alive=1
kill -0 "$daemon_pid" 2>/dev/null || alive=0

# ------------------------------------------------------------------------------ the checks
fail=0
shopt -s nullglob
verdict() { # NAME OK DETAIL
  local word=PASS
  (($2)) || { word=FAIL; fail=1; }
  echo "$word  $1: $3" | tee -a "$out/soak.log"
}
echo | tee -a "$out/soak.log"
verdict "daemon alive" "$alive" "robocald pid $daemon_pid $( ((alive)) && echo running || echo gone)"

# Samples: keys shell,lat,lon (3 decimals, as the daemon matches points).
samples_total=0
dup_total=0
missing_total=0
extra_total=0
for run_dir in "$out"/data/runs/*/; do
  run_dir=${run_dir%/}
  id=$(basename "$run_dir")
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
           /^#/ || NF == 0 { next }
           { printf "%d,%.3f,%.3f\n", $col["shell"], $col["lat_deg"], $col["lon_deg"] }' \
    "$run_dir/samples.csv" | sort >"$run_dir.keys"
  n=$(wc -l <"$run_dir.keys")
  # A place the plan measures more than once (a revisit, a reference pose) is no duplicate until
  # it is measured more often than planned.
  : >"$run_dir.planned"
  [[ -f $run_dir/plan.json ]] &&
    jq -r '.shells[] | .shell as $s | .steps[] | select(.kind == "point")
           | "\($s),\(.lat_deg),\(.lon_deg)"' "$run_dir/plan.json" |
    awk -F, '{ printf "%d,%.3f,%.3f\n", $1, $2, $3 }' >"$run_dir.planned"
  dups=$(awk 'FNR == NR { planned[$0]++; next } { seen[$0]++ }
              END { for (k in seen) { p = planned[k] > 1 ? planned[k] : 1
                                      if (seen[k] > p) d += seen[k] - p }
                    print d + 0 }' "$run_dir.planned" "$run_dir.keys")
  samples_total=$((samples_total + n))
  dup_total=$((dup_total + dups))
  status=$(jq -r .status "$run_dir/state.json")
  if [[ $status == "done" ]]; then
    sort -u "$run_dir.planned" >"$run_dir.expected"
    jq -r 'select(.event == "point_dropped") | "\(.shell),\(.lat_deg),\(.lon_deg)"' \
      "$run_dir/events.jsonl" | awk -F, '{ printf "%d,%.3f,%.3f\n", $1, $2, $3 }' |
      sort -u >"$run_dir.dropped"
    comm -23 "$run_dir.expected" "$run_dir.dropped" >"$run_dir.wanted"
    missing=$(comm -23 "$run_dir.wanted" <(sort -u "$run_dir.keys") | wc -l)
    extra=$(comm -13 "$run_dir.expected" <(sort -u "$run_dir.keys") | wc -l)
    missing_total=$((missing_total + missing))
    extra_total=$((extra_total + extra))
    echo "run $id: done, $n samples, $(wc -l <"$run_dir.wanted") wanted ($(wc -l \
      <"$run_dir.dropped") dropped by re-planning), $missing missing, $dups duplicated, $extra \
not in the plan" | tee -a "$out/soak.log"
  else
    echo "run $id: $status, $n samples, $dups duplicated" | tee -a "$out/soak.log"
  fi
done
verdict "samples exactly once" $((${#completed[@]} > 0 && dup_total == 0 && missing_total == 0 &&
  extra_total == 0)) "${#completed[@]} runs completed, $samples_total samples in all runs, \
$missing_total lost, $dup_total duplicated, $extra_total unplanned"

# RSS: mean of the last third against the first third, after a warm-up of a fifth of the soak.
read -r rss_first_kb rss_last_kb rss_max_kb < <(awk '{ rss[NR] = $2; if ($2 > max) max = $2 }
  END { w = int(NR / 5); n = NR - w; t = int(n / 3); a = 0; b = 0
        for (i = w + 1; i <= w + t; i++) a += rss[i]
        for (i = NR - t + 1; i <= NR; i++) b += rss[i]
        if (t > 0) printf "%d %d %d\n", a / t, b / t, max; else print 0, 0, max }' \
  "$out/resources.txt")
rss_ok=$((rss_first_kb > 0 && rss_last_kb * 100 <= rss_first_kb * (100 + rss_growth_pct)))
verdict "RSS flat" "$rss_ok" "mean ${rss_first_kb} kB in the first third after warm-up, \
${rss_last_kb} kB in the last (allowed +${rss_growth_pct}%), max ${rss_max_kb} kB; first sample \
$(head -1 "$out/resources.txt" | cut -d' ' -f2) kB"
fd_max=$(awk '$3 > m { m = $3 } END { print m }' "$out/resources.txt")
verdict "fds back to baseline" $((fd_end <= fd_baseline)) "baseline $fd_baseline, at the end \
$fd_end, max during the soak $fd_max"

# Faults: each must show in the window from its injection to the next one, as a pause or as the
# drivers' counters in a link_faults event. A dropped streamed bar line cannot be seen (the
# reader's lines carry no sequence number): counted, not checked.
cat "$out"/data/runs/*/events.jsonl |
  jq -c 'select((.event == "paused" and (.reason | test("prompt unanswered") | not)) or .event == "link_faults")' |
  sort >"$out/evidence.jsonl"
faults_total=$(wc -l <"$out/faults.tsv")
unseen=0
checked=0
end_iso=$(now_iso)
mapfile -t fault_lines <"$out/faults.tsv"
for i in "${!fault_lines[@]}"; do
  IFS=$'\t' read -r t kind <<<"${fault_lines[$i]}"
  next_t=$end_iso
  ((i + 1 < ${#fault_lines[@]})) && next_t=$(cut -f1 <<<"${fault_lines[$((i + 1))]}")
  case $kind in
    bar_drop) continue ;;
    bar_garbage) filter='.event == "paused" or .bar_garbage_lines or .bar_partial_lines' ;;
    val_garbage | val_drop)
      filter='.event == "paused" or .val_where_retries or .val_timeouts or .val_unsolicited_lines' ;;
    bar_disconnect) filter='.event == "paused" or .bar_disconnects' ;;
    val_stall) filter='.event == "paused" or .val_timeouts' ;;
    val_error) filter='.event == "paused" or .val_controller_errors' ;;
    *) filter='.event == "paused"' ;;
  esac
  checked=$((checked + 1))
  seen=$(jq -c --arg a "$t" --arg b "$next_t" "select(.time >= \$a and .time < \$b) | select($filter)" \
    "$out/evidence.jsonl" | head -1)
  if [[ -z $seen ]]; then
    unseen=$((unseen + 1))
    echo "fault not in the event log: $t $kind" | tee -a "$out/soak.log"
  else
    printf '%s\t%s\t%s\n' "$t" "$kind" "$seen" >>"$out/faults-seen.tsv"
  fi
done
by_kind=$(cut -f2 "$out/faults.tsv" | sort | uniq -c | awk '{ printf "%s%s %s", sep, $2, $1; sep = ", " }')
verdict "faults in the event log" $((unseen == 0)) "$faults_total injected ($by_kind); \
$((checked - unseen)) of $checked observable ones seen (bar_drop is not observable); $resumes \
resumes; $(cat "$out/churn.count" 2>/dev/null || echo 0) churned clients"
# The bar never left its range: cellsim counts each time it would have broken.
broken=$(cellsim status | grep -o 'broken_events=[0-9]*' | cut -d= -f2)
verdict "bar never over its range" $((${broken:-1} == 0)) "cellsim: ${broken:-?} bar-would-have-broken \
events ($(cellsim events | cut -c1-200))"
echo "pause reasons:" | tee -a "$out/soak.log"
jq -r 'select(.event == "paused") | .reason' "$out/evidence.jsonl" | sed 's/[0-9.]\+/N/g' |
  sort | uniq -c | sort -rn | tee -a "$out/soak.log"
if ((fail)); then echo "soak: FAIL" | tee -a "$out/soak.log"; else echo "soak: PASS" | tee -a "$out/soak.log"; fi
exit $fail
