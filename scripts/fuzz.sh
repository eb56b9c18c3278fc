#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/) with clang, ASan and UBSan into build-fuzz/ (or
# $ROBOCAL_FUZZ_BUILD_DIR) and runs each for a bounded time on a copy of its seed corpus.
#   scripts/fuzz.sh [seconds-per-harness, default 30] [harness names, default all]
#   ROBOCAL_FUZZ_SEED=N: libFuzzer's -seed (default: a new one each run)
# Exits non-zero when a harness crashes (a sanitizer report, an undocumented exception or a broken
# property) and prints the reproducer; run it again with  build-fuzz/fuzz/fuzz_<name> <file>.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-30}
shift || true
[[ $seconds =~ ^[0-9]+$ ]] || { echo "usage: $0 [seconds-per-harness] [harness ...]" >&2; exit 2; }
build=${ROBOCAL_FUZZ_BUILD_DIR:-$root/build-fuzz}
jobs=$(($(nproc) < 2 ? $(nproc) : 2))
start=$SECONDS

"$root/scripts/setup.sh"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# Only the libraries the harnesses need: no tests, daemon, simulator or command-line tool.
CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 ${ROBOCAL_DEBUG_FLAGS:--g} -DNDEBUG" \
  -DROBOCAL_BUILD_FUZZ=ON -DROBOCAL_BUILD_TESTS=OFF "-DROBOCAL_SKIP_MODULES=daemon;sim" \
  "${launcher[@]}" >/dev/null
cmake --build "$build" --target fuzz -j "$jobs"
built=$((SECONDS - start))

if (($#)); then
  names=("$@")
else
  names=()
  for dir in "$root"/fuzz/corpus/*/; do names+=("$(basename "$dir")"); done
fi

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
failed=()
for name in "${names[@]}"; do
  exe=$build/fuzz/fuzz_$name
  [[ -x $exe ]] || { echo "fuzz: no harness fuzz_$name in $build/fuzz" >&2; exit 2; }
  # A fresh copy of the seeds each run: the repository's corpus is never written to.
  work=$build/fuzz-run/$name
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp "$root/fuzz/corpus/$name/"* "$work/corpus/"
  args=(-max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1
        -artifact_prefix="$work/artifacts/")
  [[ -f $root/fuzz/$name.dict ]] && args+=(-dict="$root/fuzz/$name.dict")
  # A fixed seed (CI sets one) makes a run repeatable up to timing; unset, each run explores anew.
  [[ -n ${ROBOCAL_FUZZ_SEED:-} ]] && args+=(-seed="$ROBOCAL_FUZZ_SEED")
  status=0
  "$exe" "${args[@]}" "$work/corpus" >"$work/log" 2>&1 || status=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/log" | tail -1)
  last=$(grep -E '^#[0-9]+' "$work/log" | tail -1 || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<<"$last")
  rate=$(( ${execs:-0} / (seconds > 0 ? seconds : 1) ))
  if ((status == 0)); then
    result=ok
  else
    result="CRASH (exit $status)"
    failed+=("$name")
  fi
  printf 'fuzz_%-15s %10s execs (%6s/s)  cov %5s  ft %6s  corpus %4s  %s\n' "$name" "${execs:-?}" \
    "$rate" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$result"
  if ((status != 0)); then
    grep -E 'ERROR:|FUZZ PROPERTY FAILED|runtime error|SUMMARY' "$work/log" | head -5 | sed 's/^/    /'
    for artifact in "$work"/artifacts/*; do
      [[ -e $artifact ]] && echo "    reproducer: $artifact  (run: $exe $artifact)"
    done
    echo "    log: $work/log"
  fi
done
echo "fuzz: build ${built} s, total $((SECONDS - start)) s, ${#names[@]} harnesses x ${seconds} s"
if ((${#failed[@]})); then
  echo "fuzz: FAILED: ${failed[*]}" >&2
  exit 1
fi
