#!/usr/bin/env bash
# Builds (if needed) and runs the libFuzzer targets of fuzz/, one after the other, each for a
# given time on a scratch copy of its seed corpus; prints executions, executions/s, coverage and
# the files of any finding. Exits 1 if any target reported a finding (crash, sanitizer report,
# timeout, out-of-memory, leak), 2 on a usage or build error.
#
# usage: fuzz/run_fuzzers.sh [SECONDS_PER_TARGET] [TARGET...]
#   SECONDS_PER_TARGET  default 600
#   TARGET              default: all (FuzzLevelSetIO FuzzMeshObj FuzzMeshPly FuzzMeshStl
#                       FuzzPolyline FuzzMeshDocument FuzzPointTable FuzzConfig)
# environment:
#   BUILD_DIR      the VDBMATCH_FUZZ build tree (default: <repo>/build-fuzz; configured with
#                  clang if it has no CMakeCache.txt)
#   FUZZ_OUT       where logs, corpora and findings are kept (default: $BUILD_DIR/fuzz-runs)
#   FUZZ_JOBS      parallel compile jobs (default 2)
#   FUZZ_NICE      nice level of builds and runs (default 10)
#   FUZZ_KEEP_GOING  1: fork mode (-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1):
#                  a target keeps running after a finding and collects every finding of the run
#   FUZZ_ARGS      extra libFuzzer flags
set -u -o pipefail

ALL_TARGETS=(FuzzLevelSetIO FuzzMeshObj FuzzMeshPly FuzzMeshStl FuzzPolyline FuzzMeshDocument
             FuzzPointTable FuzzConfig)
SECONDS_PER_TARGET=${1:-600}
shift $(( $# > 0 ? 1 : 0 ))
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=("${ALL_TARGETS[@]}")
if ! [[ "$SECONDS_PER_TARGET" =~ ^[0-9]+$ ]] || [ "$SECONDS_PER_TARGET" -lt 1 ]; then
    echo "run_fuzzers.sh: SECONDS_PER_TARGET must be a positive integer, got '$SECONDS_PER_TARGET'" >&2
    exit 2
fi
for t in "${TARGETS[@]}"; do
    if [[ ! " ${ALL_TARGETS[*]} " =~ " $t " ]]; then
        echo "run_fuzzers.sh: unknown target '$t' (known: ${ALL_TARGETS[*]})" >&2
        exit 2
    fi
done

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$REPO/build-fuzz}
FUZZ_OUT=${FUZZ_OUT:-$BUILD_DIR/fuzz-runs}
FUZZ_JOBS=${FUZZ_JOBS:-2}
FUZZ_NICE=${FUZZ_NICE:-10}

# ------------------------------------------------------------------ build
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
    CC=clang CXX=clang++ cmake -S "$REPO" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DVDBMATCH_FUZZ=ON -DVDBMATCH_BUILD_TESTS=OFF -DVDBMATCH_BUILD_BENCHMARKS=OFF \
        -DVDBMATCH_BUILD_TOOLS=OFF || exit 2
fi
nice -n "$FUZZ_NICE" cmake --build "$BUILD_DIR" -j "$FUZZ_JOBS" --target "${TARGETS[@]}" || exit 2

# ------------------------------------------------------------------ run
# UBSan reports are fatal (they are findings); leaks are reported; the limits of the brief:
# 10 s per input, 2 GB RSS, 2 GB per allocation.
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
# Leaks inside libopenvdb on corrupt grids are upstream (fuzz/lsan.supp says why).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$REPO/fuzz/lsan.supp:print_suppressions=0}
KEEP_GOING_ARGS=""
if [ "${FUZZ_KEEP_GOING:-0}" = 1 ]; then
    KEEP_GOING_ARGS="-fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1"
fi
STAMP=$(date +%Y%m%d-%H%M%S)
findings=0
summary=()
for t in "${TARGETS[@]}"; do
    run="$FUZZ_OUT/$t-$STAMP"
    mkdir -p "$run/corpus" "$run/artifacts"
    cp "$REPO/fuzz/corpus/$t/"* "$run/corpus/" 2>/dev/null
    # Per-process scratch files of the targets go to $TMPDIR.
    export TMPDIR="$run/tmp"
    mkdir -p "$TMPDIR"
    echo "== $t: ${SECONDS_PER_TARGET}s, log $run/log.txt"
    start=$(date +%s)
    # shellcheck disable=SC2086
    nice -n "$FUZZ_NICE" "$BUILD_DIR/fuzz/$t" "$run/corpus" -max_total_time="$SECONDS_PER_TARGET" \
        -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$run/artifacts/" $KEEP_GOING_ARGS ${FUZZ_ARGS:-} >"$run/log.txt" 2>&1
    status=$?
    elapsed=$(( $(date +%s) - start ))
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$run/log.txt" | tail -1)
    if [ -z "$execs" ]; then
        execs=$(grep -o '^#[0-9]*' "$run/log.txt" | tail -1 | tr -d '#')
    fi
    rate=$(( ${execs:-0} / (elapsed > 0 ? elapsed : 1) ))
    last=$(grep -E '^#[0-9]+.*cov: ' "$run/log.txt" | tail -1)
    cov=$(sed -n 's/.*cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
    crashes=$(find "$run/artifacts" -type f | sort)
    if [ $status -ne 0 ] || [ -n "$crashes" ]; then
        findings=1
        result="FINDING (exit $status)"
        grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$run/log.txt" | head -5
        for c in $crashes; do echo "   finding file: $c"; done
    else
        result="none"
    fi
    echo "   $t: ${elapsed}s, ${execs:-?} executions, ${rate} exec/s, cov ${cov:-?}, ft ${ft:-?}, findings: $result"
    echo "   final line: $last"
    summary+=("$(printf '%-17s %6ss %12s %8s %6s %6s  %s' "$t" "$elapsed" "${execs:-?}" "$rate" \
                "${cov:-?}" "${ft:-?}" "$result")")
done

echo
printf '%-17s %7s %12s %8s %6s %6s  %s\n' target time executions exec/s cov ft findings
for line in "${summary[@]}"; do echo "$line"; done
exit $findings
