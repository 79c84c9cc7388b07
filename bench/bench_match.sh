#!/usr/bin/env bash
# Benchmark of the whole match on the bundled 3D pair (assets/starfish_a.vdb -> starfish_b.vdb):
# for each level range (default 4..7 and 4..8) prints the wall time, the peak memory (resident
# set, from GNU time), and per level the cells, unknowns (and their fraction of the dense
# lattice), iterations, energy and gradient evaluations, and seconds; from report.json.
# Usage: bench/bench_match.sh [VDB_MATCH] [RANGE...]   e.g. bench/bench_match.sh build/tools/vdb_match/vdb_match 4..7
# Environment: BENCH_SOURCE, BENCH_TARGET override the pair; BENCH_ARGS adds options; BENCH_OUT
# keeps the outputs (default: a temporary directory); BENCH_OPTIMIZERS="ncg lbfgs" runs each
# range once per optimizer (default: ncg), to compare the energy reached and the time taken.
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
for range in "${RANGES[@]}"; do
  for optimizer in ${BENCH_OPTIMIZERS:-ncg}; do
    dir="$OUT/levels-$range-$optimizer"
    mkdir -p "$dir"
    /usr/bin/time -f '%e %M' -o "$dir/time.txt" \
        "$VDB_MATCH" "$SOURCE" "$TARGET" -o "$dir" --levels "$range" --optimizer "$optimizer" --quiet ${BENCH_ARGS:-} >"$dir/stdout.txt"
    read -r wall rssKb <"$dir/time.txt"
    "$PYTHON" - "$dir/report.json" "$range" "$wall" "$rssKb" "$optimizer" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
rng, wall, rss = sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
print(f"\nlevels {rng}, optimizer {sys.argv[5]}: wall {wall:.1f} s, peak memory {rss / 1024:.0f} MB, status {r['status']}, "
      f"energy {r['result']['energy']:.6e}, residual mean {r['result']['residual']['meanUnit']:.2e} "
      f"max {r['result']['residual']['maxUnit']:.2e} (unit box), min det {r['result']['minJacobian']:.3f}")
print(f"{'level':>5} {'cells':>9} {'unknowns':>9} {'%dense':>7} {'iters':>6} {'E evals':>8} {'grad evals':>10} "
      f"{'CG its':>7} {'fields s':>8} {'lattice s':>9} {'descent s':>9}  status")
for l in r["levels"]:
    s = l["seconds"]
    print(f"{l['level']:>5} {l['cells']:>9} {l['unknowns']:>9} {100 * l['nodeFractionOfDense']:>6.1f}% "
          f"{l['iterations']:>6} {l['energyEvaluations']:>8} {l['gradientEvaluations']:>10} "
          f"{l['metricIterations']:>7} {s['fields']:>8.2f} {s['lattice']:>9.2f} {s['descent']:>9.2f}  {l['status']}")
PY
  done
done
[ -n "${BENCH_OUT:-}" ] || rm -rf "$OUT"
