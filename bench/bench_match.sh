#!/usr/bin/env bash
# Benchmark of the whole match on the bundled 3D pair (assets/starfish_a.vdb -> starfish_b.vdb):
# for each level range (default 4..7 and 4..8) prints the wall time, the peak memory (resident
# set, from GNU time), and per level the cells, unknowns (and their fraction of the dense
# lattice), iterations, energy and gradient evaluations, and seconds; from report.json.
# Usage: bench/bench_match.sh [VDB_MATCH] [RANGE...]   e.g. bench/bench_match.sh build/tools/vdb_match/vdb_match 4..7
# Environment: BENCH_SOURCE, BENCH_TARGET override the pair; BENCH_ARGS adds options; BENCH_OUT
# keeps the outputs (default: a temporary directory); BENCH_OPTIMIZERS="ncg lbfgs" runs each
# range once per optimizer (default: ncg), to compare the energy reached and the time taken.
# BENCH_CONTROLS=N adds N runs per range whose metric weight tau is changed in its 7th digit
# (--metric-tau 0.5 (1 + k 2e-7), k = 1..N): a change of the last digits that moves the
# iteration counts as much as any change of the arithmetic does (the fine levels' energy test is
# chaotic: on the starfish pair at 4..8, level 7 took 78 or 121 iterations for two builds that
# differ in the last bits). A summary line then gives the wall time of the 1 + N runs (min,
# median, max). The per-level "ms/eval" column, descent seconds per energy evaluation, does not
# depend on the iteration counts: compare builds on it, and on the summary, not on one run.
set -euo pipefail
cd "$(dirname "$0")/.."
VDB_MATCH=${1:-build/tools/vdb_match/vdb_match}
shift || true
RANGES=("$@")
[ ${#RANGES[@]} -gt 0 ] || RANGES=(4..7 4..8)
SOURCE=${BENCH_SOURCE:-assets/starfish_a.vdb}
TARGET=${BENCH_TARGET:-assets/starfish_b.vdb}
OUT=${BENCH_OUT:-$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-bench.XXXXXX")}
PYTHON=python3
[ -x /usr/bin/python3 ] && PYTHON=/usr/bin/python3
[ -x /usr/bin/time ] || { echo "bench_match.sh: needs GNU time (apt-get install -y time)" >&2; exit 1; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "pair: $SOURCE -> $TARGET"
CONTROLS=${BENCH_CONTROLS:-0}
case "$CONTROLS" in ''|*[!0-9]*) echo "bench_match.sh: BENCH_CONTROLS must be a count, got '$CONTROLS'" >&2; exit 1 ;; esac
if [ "$CONTROLS" -gt 0 ] && [[ " ${BENCH_ARGS:-} " == *" --metric-tau "* ]]; then
  echo "bench_match.sh: BENCH_CONTROLS changes --metric-tau; do not pass it in BENCH_ARGS" >&2; exit 1
fi
for range in "${RANGES[@]}"; do
  for optimizer in ${BENCH_OPTIMIZERS:-ncg}; do
   walls=()
   for k in $(seq 0 "$CONTROLS"); do
    dir="$OUT/levels-$range-$optimizer"
    control=()
    label=""
    if [ "$k" -gt 0 ]; then
      dir="$dir-control$k"
      tau=$("$PYTHON" -c "print(repr(0.5 * (1 + $k * 2e-7)))")
      control=(--metric-tau "$tau")
      label=", control $k (--metric-tau $tau)"
    fi
    mkdir -p "$dir"
    /usr/bin/time -f '%e %M' -o "$dir/time.txt" \
        "$VDB_MATCH" "$SOURCE" "$TARGET" -o "$dir" --levels "$range" --optimizer "$optimizer" --quiet ${BENCH_ARGS:-} "${control[@]}" >"$dir/stdout.txt"
    read -r wall rssKb <"$dir/time.txt"
    walls+=("$wall")
    "$PYTHON" - "$dir/report.json" "$range" "$wall" "$rssKb" "$optimizer$label" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
rng, wall, rss = sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
print(f"\nlevels {rng}, optimizer {sys.argv[5]}: wall {wall:.1f} s, peak memory {rss / 1024:.0f} MB, status {r['status']}, "
      f"energy {r['result']['energy']:.6e}, residual mean {r['result']['residual']['meanUnit']:.2e} "
      f"max {r['result']['residual']['maxUnit']:.2e} (unit box), min det {r['result']['minJacobian']:.3f}")
print(f"{'level':>5} {'cells':>9} {'unknowns':>9} {'%dense':>7} {'iters':>6} {'E evals':>8} {'grad evals':>10} "
      f"{'CG its':>7} {'fields s':>8} {'lattice s':>9} {'descent s':>9} {'ms/eval':>8}  status")
for l in r["levels"]:
    s = l["seconds"]
    evals = l["energyEvaluations"] + l["gradientEvaluations"]
    perEval = f"{1000 * s['descent'] / evals:>8.2f}" if evals else f"{'-':>8}"
    print(f"{l['level']:>5} {l['cells']:>9} {l['unknowns']:>9} {100 * l['nodeFractionOfDense']:>6.1f}% "
          f"{l['iterations']:>6} {l['energyEvaluations']:>8} {l['gradientEvaluations']:>10} "
          f"{l['metricIterations']:>7} {s['fields']:>8.2f} {s['lattice']:>9.2f} {s['descent']:>9.2f} {perEval}  {l['status']}")
PY
   done
   if [ "$CONTROLS" -gt 0 ]; then
     "$PYTHON" -c "
import statistics, sys
w = sorted(float(x) for x in sys.argv[2:])
print(f'\nlevels {sys.argv[1]}, optimizer $optimizer: wall over {len(w)} runs (1 + {len(w) - 1} controls): '
      f'min {w[0]:.1f} s, median {statistics.median(w):.1f} s, max {w[-1]:.1f} s')" "$range" "${walls[@]}"
   fi
  done
done
[ -n "${BENCH_OUT:-}" ] || rm -rf "$OUT"
