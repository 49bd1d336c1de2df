#!/usr/bin/env bash
# Builds the libFuzzer harnesses (build-fuzz, clang, ASan + UBSan) and fuzzes each one for a
# bounded time on a fresh copy of its seed corpus; see docs/fuzzing.md.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [--runs N] [--targets "xml ply obj serialized vol btf exr cube experiment"]
#   scripts/fuzz.sh --replay DIR [TARGET]    run TARGET's harness (default xml) once over every
#                                            file in DIR and report the share of located errors
#
# Prints per target the inputs executed, exec/s, the harness' tally (accepted / located errors)
# and any findings; exits 1 when a harness found a crash, a hang (-timeout), a leak, an
# out-of-memory or a sanitizer report. Work files (corpora, logs, findings) go to
# build-fuzz/fuzz-run/<target>/.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

SECONDS_PER_TARGET=30
RUNS=""
TARGETS="xml ply obj serialized vol btf exr cube experiment"
REPLAY=""
REPLAY_TARGET=xml
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) RUNS="$2"; shift 2 ;;
    --targets) TARGETS="$2"; shift 2 ;;
    --replay)
      REPLAY="$(cd "$2" && pwd)"; shift 2
      if [ $# -gt 0 ] && [[ "$1" != --* ]]; then REPLAY_TARGET="$1"; shift; fi ;;
    [0-9]*) SECONDS_PER_TARGET="$1"; shift ;;
    *) echo "usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [--runs N] [--targets LIST] | --replay DIR [TARGET]" >&2
       exit 2 ;;
  esac
done

# FEMTO_FUZZ_BUILD: another build folder configured with FEMTO_FUZZ=ON (scripts/test.sh passes
# its sanitizer build, which builds the tests and the harnesses in one clang configuration).
BUILD=${FEMTO_FUZZ_BUILD:-build-fuzz}
if [ -f "$BUILD/CMakeCache.txt" ] && ! grep -q '^FEMTO_FUZZ:BOOL=ON$' "$BUILD/CMakeCache.txt"; then
  echo "scripts/fuzz.sh: $BUILD is not configured with -DFEMTO_FUZZ=ON (clang)" >&2
  exit 2
fi
LAUNCHER=()
if command -v ccache >/dev/null; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [ ! -f "$BUILD/build.ninja" ]; then
  # -O1 with line tables: libFuzzer's usual optimisation level, and half the compile time of
  # -O2 -g (scripts/test.sh builds this on every run).
  CC=clang CXX=clang++ cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
    -DFEMTO_TESTS=OFF -DFEMTO_FUZZ=ON "${LAUNCHER[@]}" >/dev/null
fi
# The harnesses and what they load (libfemto, every plugin, the seeds), not the CLI.
cmake --build "$BUILD" -j "$(nproc)" --target femto_fuzz_xml femto_fuzz_ply femto_fuzz_obj femto_fuzz_serialized \
  femto_fuzz_vol femto_fuzz_btf femto_fuzz_exr femto_fuzz_cube femto_fuzz_experiment >/dev/null

# Leaks are reported (scripts/test.sh's suppressions: OpenImageIO's own leak). UBSan stops at
# the first report so that libFuzzer records it as a crash.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:symbolize=1"
export LSAN_OPTIONS="suppressions=$ROOT/scripts/lsan-suppressions.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

# Prints the summary of one harness run from its log; returns 1 on findings.
summarize() {
  local name="$1" log="$2" artifacts="$3" status="$4"
  local execs rate tally findings
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  tally=$(sed -n 's/^femto-fuzz tally: //p' "$log" | tail -1)
  findings=$(find "$artifacts" -type f \( -name 'crash-*' -o -name 'timeout-*' -o -name 'leak-*' \
    -o -name 'oom-*' \) | sort)
  printf '%-4s %s inputs, %s exec/s; %s\n' "$name" "${execs:-?}" "${rate:-?}" "${tally:-no tally}"
  if [ -n "$findings" ] || [ "$status" -ne 0 ]; then
    echo "$name: FOUND something (exit $status); log: $log" >&2
    for f in $findings; do echo "  $f" >&2; done
    grep -m 3 -E '^(==[0-9]+==ERROR|SUMMARY|femto-fuzz finding|.*runtime error)' "$log" >&2 || true
    return 1
  fi
  echo "$name: nothing found"
}

if [ -n "$REPLAY" ]; then
  # -runs=0 runs each file once (and an empty input); libFuzzer's leak check would run some
  # twice, skewing the tally.
  work="$BUILD/fuzz-run/replay-$REPLAY_TARGET"
  rm -rf "$work"
  mkdir -p "$work/artifacts"
  status=0
  "$BUILD/bin/femto_fuzz_$REPLAY_TARGET" -runs=0 -detect_leaks=0 -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$work/artifacts/" "$REPLAY" 2>"$work/log" || status=$?
  summarize "$REPLAY_TARGET" "$work/log" "$work/artifacts" "$status"
  exit
fi

failed=0
for t in $TARGETS; do
  work="$BUILD/fuzz-run/$t"
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp "$BUILD/fuzz/seeds/$t/"* "$work/corpus/"
  args=(-max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048
        -print_final_stats=1 -artifact_prefix="$work/artifacts/")
  if [ -n "$RUNS" ]; then args+=(-runs="$RUNS"); fi
  if [ "$t" = xml ]; then args+=(-dict=fuzz/xml.dict); fi
  status=0
  "$BUILD/bin/femto_fuzz_$t" "${args[@]}" "$work/corpus" 2>"$work/log" || status=$?
  summarize "$t" "$work/log" "$work/artifacts" "$status" || failed=1
done
exit $failed
