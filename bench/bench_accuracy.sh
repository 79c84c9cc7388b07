#!/usr/bin/env bash
# Accuracy benchmark on synthetic pairs with a known ground-truth map g (issue 8, item 3).
#
# Generates the pairs (bench/accuracy/make_pairs.py: a creature and an animal in 3D and a figure
# in 2D, moved by articulated limb motions (moderate and large), twists and swirls, and a mild
# anisotropic stretch; the target is g applied to the source's vertices), then for every pair
# and energy runs vdb_match forward (source -> target) and reverse (target -> source) with the
# same options, `vdb_match consistency` on the two deformations, and prints one row per pair x
# energy (bench/accuracy/score.py; lengths in unit-box units):
#   fwd s, rev s  wall seconds of the forward and the reverse match
#   resid         mean |d2(phi(v))| over M1's vertices (report.json result.residual.meanUnit)
#   err mean/p95  mean and 95th percentile of |phi(v) - g(v)| over M1's vertices
#   rev err       mean |psi(g(v)) - v| over M2's vertices (the reverse match against g^-1)
#   motion        mean |g(v) - v|, for reference
#   psi.phi       mean |psi(phi(v)) - v| over M1's vertices (vdb_match consistency)
#   min det       min det D phi of the forward match (report.json result.minJacobian)
# and per energy the mean of these over the pairs. results.tsv in the output directory holds the
# same and more (max errors, reverse figures, iterations, statuses, the error on the vertices g
# keeps still and on those it moves: score.py).
#
# Usage: bench/bench_accuracy.sh [VDB_MATCH] [--pairs a,b,...] [--levels3d 4..7] [--levels2d 4..9]
#            [--energies symmetric,directional] [--out DIR] [--extra "ARGS"] [--landmarks]
#            [--resampled | --scan]
#   VDB_MATCH   default build/tools/vdb_match/vdb_match
#   --pairs     names, or a set: all (default; the seventeen pairs of make_pairs.py --list:
#               a creature, an animal and a figure, near-isometric, large-motion and stretch
#               pairs) or speed (the eight creature and figure pairs that the speed issue's
#               figures in docs/performance.md use: make_pairs.py --list speed)
#   --levels3d  default 4..8 (the 3D default of vdb_match); --levels2d default 4..9
#   --energies  default symmetric,directional
#   --out DIR   keep pairs and outputs in DIR (pairs are regenerated only when missing or older
#               than make_pairs.py); default: a temporary directory, removed at the end
#   --extra     more vdb_match match options, e.g. --extra "--threads 1 --energy-tolerance 3e-2"
#               (--threads is also passed to consistency)
#   --landmarks give vdb_match the pair's landmarks (make_pairs.py: 5 farthest-point samples of the source
#               and their true images), forward A B and reverse B A
#   --resampled match against the target sampled independently of the source (make_pairs.py
#               target_resampled.*: re-meshed from its level set in 3D, resampled by arc length
#               in 2D); the reverse error then carries g(v) through psi with `vdb_match apply`
#   --scan      as --resampled, against that target with a scanner's noise (make_pairs.py
#               target_scan.*: Gaussian, std 0.2% of the source's box diagonal, per vertex)
# Exit status: 0, or 1 with a message if generation, a match, consistency or scoring fails.
set -euo pipefail

usage() { sed -n '/^# Usage:/,/^# Exit status/p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "bench_accuracy.sh: $*" >&2; exit 1; }

VDB_MATCH=
PAIRS=all
LEVELS3D=4..8
LEVELS2D=4..9
ENERGIES=symmetric,directional
OUT=
EXTRA=
LANDMARKS=0
RESAMPLED=0
TARGET_NAME=target_resampled
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --resampled) RESAMPLED=1; shift ;;
    --scan) RESAMPLED=1; TARGET_NAME=target_scan; shift ;;
    --landmarks) LANDMARKS=1; shift ;;
    --pairs|--levels3d|--levels2d|--energies|--out|--extra)
      [ $# -ge 2 ] || die "$1 needs a value"
      case "$1" in
        --pairs) PAIRS=$2 ;; --levels3d) LEVELS3D=$2 ;; --levels2d) LEVELS2D=$2 ;;
        --energies) ENERGIES=$2 ;; --out) OUT=$2 ;; --extra) EXTRA=$2 ;;
      esac
      shift 2 ;;
    --pairs=*) PAIRS=${1#*=}; shift ;;
    --levels3d=*) LEVELS3D=${1#*=}; shift ;;
    --levels2d=*) LEVELS2D=${1#*=}; shift ;;
    --energies=*) ENERGIES=${1#*=}; shift ;;
    --out=*) OUT=${1#*=}; shift ;;
    --extra=*) EXTRA=${1#*=}; shift ;;
    -*) usage >&2; die "unknown option $1" ;;
    *) [ -z "$VDB_MATCH" ] || die "unexpected argument $1"; VDB_MATCH=$1; shift ;;
  esac
done

ROOT=$(cd "$(dirname "$0")/.." && pwd)
[ -n "$VDB_MATCH" ] || VDB_MATCH=$ROOT/build/tools/vdb_match/vdb_match
case "$VDB_MATCH" in /*) ;; */*) VDB_MATCH=$PWD/$VDB_MATCH ;; esac
[ -x "$VDB_MATCH" ] || command -v "$VDB_MATCH" >/dev/null 2>&1 || die "no executable $VDB_MATCH (build it first)"
PYTHON=python3
[ -x /usr/bin/python3 ] && PYTHON=/usr/bin/python3
MAKE_PAIRS=$ROOT/bench/accuracy/make_pairs.py
SCORE=$ROOT/bench/accuracy/score.py

read -r -a EXTRA_ARGS <<<"$EXTRA"
THREAD_ARGS=()
for ((i = 0; i < ${#EXTRA_ARGS[@]}; i++)); do
  case "${EXTRA_ARGS[i]}" in
    --threads) THREAD_ARGS=(--threads "${EXTRA_ARGS[i + 1]:-}") ;;
    --threads=*) THREAD_ARGS=("${EXTRA_ARGS[i]}") ;;
  esac
done
case "$PAIRS" in all|speed) PAIRS=$("$PYTHON" "$MAKE_PAIRS" --list "$PAIRS" | paste -sd, -) ;; esac
IFS=, read -r -a PAIR_LIST <<<"$PAIRS"
IFS=, read -r -a ENERGY_LIST <<<"$ENERGIES"
for e in "${ENERGY_LIST[@]}"; do
  case "$e" in symmetric|directional) ;; *) die "unknown energy '$e' (symmetric or directional)" ;; esac
done

source "$ROOT/bench/accuracy/ensure_pairs.sh"
output_dir accuracy

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "vdb_match: $VDB_MATCH ($("$VDB_MATCH" --version 2>&1 | head -n1))"
echo "options: pairs $PAIRS; levels 3D $LEVELS3D, 2D $LEVELS2D; energies $ENERGIES; extra '${EXTRA}'$([ $LANDMARKS = 0 ] || echo '; landmarks')$([ $RESAMPLED = 0 ] || echo "; targets $TARGET_NAME")"
echo "output: $OUT$([ $KEEP = 1 ] || echo ' (temporary)')"

# --- pairs -----------------------------------------------------------------------------------
ensure_pairs "$OUT" "${PAIR_LIST[@]}"
echo

# --- matches ---------------------------------------------------------------------------------
run_match() {  # SOURCE TARGET DIR LEVELS ENERGY [LANDMARKS_A LANDMARKS_B]; sets WALL
  local dir=$3 start end rc=0
  mkdir -p "$dir"
  local cmd=("$VDB_MATCH" match "$1" "$2" -o "$dir" --levels "$4" --energy "$5" --quiet "${EXTRA_ARGS[@]}")
  [ $# -lt 7 ] || cmd+=(--landmarks "$6" "$7")
  start=$(date +%s.%N)
  "${cmd[@]}" >"$dir/stdout.txt" 2>"$dir/stderr.txt" || rc=$?
  end=$(date +%s.%N)
  if [ $rc -ne 0 ] || [ ! -f "$dir/report.json" ] || [ ! -f "$dir/deformed.obj" ] || [ ! -f "$dir/deformation.vdb" ]; then
    echo "bench_accuracy.sh: match failed (exit $rc): ${cmd[*]}" >&2
    tail -n 20 "$dir/stderr.txt" >&2
    exit 1
  fi
  WALL=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", b - a }')
}

TSV=$OUT/results.tsv
rm -f "$TSV"
"$PYTHON" "$SCORE" --header
for energy in "${ENERGY_LIST[@]}"; do
  for p in "${PAIR_LIST[@]}"; do
    pd=$OUT/pairs/$p
    dim=$("$PYTHON" -c 'import json,sys; print(json.load(open(sys.argv[1]))["dimension"])' "$pd/pair.json")
    if [ "$dim" = 3 ]; then ext=obj; levels=$LEVELS3D; else ext=polyline; levels=$LEVELS2D; fi
    rd=$OUT/runs/$p/$energy
    marks=()
    [ $LANDMARKS = 0 ] || marks=("$pd/landmarks_source.csv" "$pd/landmarks_target.csv")
    target=$pd/target.$ext
    [ $RESAMPLED = 0 ] || target=$pd/$TARGET_NAME.$ext
    run_match "$pd/source.$ext" "$target" "$rd/forward" "$levels" "$energy" "${marks[@]}"; fwall=$WALL
    [ $LANDMARKS = 0 ] || marks=("$pd/landmarks_target.csv" "$pd/landmarks_source.csv")
    run_match "$target" "$pd/source.$ext" "$rd/reverse" "$levels" "$energy" "${marks[@]}"; rwall=$WALL
    reverse_points=()
    if [ $RESAMPLED = 1 ]; then  # psi(g(v)): the original target's vertices carried by psi
      "$VDB_MATCH" apply "$rd/reverse/deformation.vdb" "$pd/target.$ext" -o "$rd/reverse/psi_of_g.$ext" \
          "${THREAD_ARGS[@]}" >"$rd/reverse/apply.log" 2>&1 || { cat "$rd/reverse/apply.log" >&2; die "apply failed for $p"; }
      reverse_points=(--reverse-points "$rd/reverse/psi_of_g.$ext")
    fi
    "$VDB_MATCH" consistency "$rd/forward/deformation.vdb" "$rd/reverse/deformation.vdb" \
        --source "$pd/source.$ext" --target "$pd/target.$ext" --json "${THREAD_ARGS[@]}" \
        >"$rd/consistency.json" 2>"$rd/consistency.stderr" \
        || { cat "$rd/consistency.stderr" >&2; die "consistency failed for $p ($energy)"; }
    "$PYTHON" "$SCORE" --pair "$pd" --forward "$rd/forward" --reverse "$rd/reverse" \
        --consistency "$rd/consistency.json" --energy "$energy" --levels "$levels" \
        --wall "$fwall" --reverse-wall "$rwall" --tsv "$TSV" "${reverse_points[@]}" \
        || die "scoring failed for $p ($energy)"
  done
done

# --- means per energy ------------------------------------------------------------------------
"$PYTHON" - "$TSV" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
print()
keys = ("forward_wall_s", "residual_mean", "err_mean", "err_p95", "reverse_err_mean", "motion_mean", "psi_phi_mean")
for dim in ("3", "2"):
    for energy in dict.fromkeys(r["energy"] for r in rows):
        sel = [r for r in rows if r["energy"] == energy and r["dim"] == dim]
        if not sel:
            continue
        m = {k: sum(float(r[k]) for r in sel) / len(sel) for k in keys}
        print(f"mean {dim}D {energy:<11} over {len(sel)} pairs: fwd {m['forward_wall_s']:.1f} s, resid {m['residual_mean']:.2e}, "
              f"err mean {m['err_mean']:.2e}, err p95 {m['err_p95']:.2e}, rev err {m['reverse_err_mean']:.2e}, "
              f"motion {m['motion_mean']:.2e}, psi.phi {m['psi_phi_mean']:.2e}, min det {min(float(r['min_det']) for r in sel):.3f}")
PY
[ $KEEP = 0 ] || echo "results: $TSV"
