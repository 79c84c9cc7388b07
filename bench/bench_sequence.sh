#!/usr/bin/env bash
# Warm starts along a sequence (issue: many shapes): the same frame sequence matched frame by
# frame from the identity and with `batch --warm-start`, one after the other, scored against the
# known map.
#
# Generates the sequence once (bench/accuracy/make_sequence.py: the creature of the accuracy
# benchmark, 9 frames, three limbs turning 45-75 degrees in all while it drifts), runs
#   vdb_match batch --sequence frame.####.obj --frames 1-9 [--warm-start] -- --levels LEVELS
# both ways, collects them (sequence/deformed.####.obj: frame 1 carried to every frame) and
# prints per job (bench/accuracy/score_sequence.py; unit-box units) the match time, iterations
# per level, the error of the step |phi_k(v) - v'| and of the composed map from frame 1, min det;
# then the direct match from the first to the last frame, scored the same way.
#
# Usage: bench/bench_sequence.sh [VDB_MATCH] [--levels 4..7] [--warm-start-level L]
#            [--threads N] [--out DIR] [--motion limbs|arm-up] [--frames N]
#   VDB_MATCH   default build/tools/vdb_match/vdb_match
#   --levels    default 4..7
#   --warm-start-level  passed to the warm-started matches (default: match's)
#   --threads   threads of each match (default 2); the jobs run one at a time either way
#   --out DIR   keep the frames and the batches in DIR (default: a temporary directory)
#   --motion, --frames  the sequence (make_sequence.py; default limbs, 9 frames); arm-up cuts
#               the accuracy benchmark's 100-degree arm raise into equal steps
# Exit status: 0, or 1 with a message.
set -euo pipefail

usage() { sed -n '/^# Usage:/,/^# Exit status/p' "$0" | sed 's/^# \{0,1\}//'; }
die() { echo "bench_sequence.sh: $*" >&2; exit 1; }

HERE=$(cd "$(dirname "$0")" && pwd)
VDB_MATCH=
LEVELS=4..7
WARM_LEVEL=
THREADS=2
OUT=
MOTION=limbs
FRAMES_ASKED=9
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --levels|--warm-start-level|--threads|--out|--motion|--frames)
      [ $# -ge 2 ] || die "$1 needs a value"
      case "$1" in
        --levels) LEVELS=$2 ;;
        --warm-start-level) WARM_LEVEL=$2 ;;
        --threads) THREADS=$2 ;;
        --out) OUT=$2 ;;
        --motion) MOTION=$2 ;;
        --frames) FRAMES_ASKED=$2 ;;
      esac
      shift 2 ;;
    -*) die "unknown option $1 (--help)" ;;
    *) [ -z "$VDB_MATCH" ] || die "one VDB_MATCH only"; VDB_MATCH=$1; shift ;;
  esac
done
VDB_MATCH=${VDB_MATCH:-$HERE/../build/tools/vdb_match/vdb_match}
[ -x "$VDB_MATCH" ] || die "no executable vdb_match at $VDB_MATCH (build first, or pass its path)"
PYTHON=/usr/bin/python3
"$PYTHON" -c "import numpy, pyopenvdb" 2>/dev/null || die "$PYTHON needs numpy and pyopenvdb (python3-numpy, python3-openvdb)"
if [ -z "$OUT" ]; then
  OUT=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-sequence.XXXXXX")
  trap 'rm -rf "$OUT"' EXIT
fi
mkdir -p "$OUT"
SEQ=$OUT/frames-$MOTION-$FRAMES_ASKED
if [ ! -s "$SEQ/sequence.json" ] || [ "$SEQ/sequence.json" -ot "$HERE/accuracy/make_sequence.py" ]; then
  "$PYTHON" "$HERE/accuracy/make_sequence.py" "$SEQ" --frames "$FRAMES_ASKED" --motion "$MOTION" ||
    die "make_sequence.py failed"
fi
FRAMES=$("$PYTHON" -c "import json,sys; print(json.load(open(sys.argv[1]))['frames'])" "$SEQ/sequence.json")

run() { # run LABEL [BATCH OPTIONS...] -- MATCH OPTIONS...
  local label=$1
  shift
  local dir=$OUT/$label-$MOTION-$FRAMES_ASKED-$LEVELS
  "$VDB_MATCH" batch --sequence "$SEQ/frame.####.obj" --frames "1-$FRAMES" -o "$dir" --quiet \
    --jobs 1 --threads-per-job "$THREADS" "$@" >/dev/null || die "batch $label failed (see $dir)"
  "$VDB_MATCH" batch collect "$dir" --quiet >/dev/null || die "collect $label failed"
  "$PYTHON" "$HERE/accuracy/score_sequence.py" "$SEQ" "$dir" "$label"
}

echo "sequence: $(cat "$SEQ/sequence.json" | "$PYTHON" -c "import json,sys; print(json.load(sys.stdin)['description'])")"
echo "levels $LEVELS, $THREADS threads per match, $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores"
printf '%-6s %-6s %7s %-22s %9s %9s %9s %7s\n' label step "match s" "iterations" "step err" "p95" "composed" "min det"
run cold -- --levels "$LEVELS" --no-inverse --no-jacobian
WARM_ARGS=()
[ -n "$WARM_LEVEL" ] && WARM_ARGS=(--warm-start-level "$WARM_LEVEL")
run warm --warm-start -- --levels "$LEVELS" --no-inverse --no-jacobian "${WARM_ARGS[@]}"
# The direct match from the first to the last frame, for comparison with the composed maps.
DIRECT=$OUT/direct-$MOTION-$FRAMES_ASKED-$LEVELS
LAST=$(printf '%04d' "$FRAMES")
"$VDB_MATCH" match "$SEQ/frame.0001.obj" "$SEQ/frame.$LAST.obj" -o "$DIRECT" --levels "$LEVELS" \
  --threads "$THREADS" --quiet --no-inverse --no-jacobian >/dev/null || die "the direct match failed"
"$PYTHON" - "$SEQ/frame.0001.obj" "$SEQ/frame.$LAST.obj" "$DIRECT" "$HERE/accuracy" <<'PY'
import json, sys
sys.path.insert(0, sys.argv[4])
import numpy as np
from score_sequence import vertices
first, last, d = sys.argv[1:4]
r = json.load(open(d + "/report.json"))
s = r["placement"]["scale"]
e = np.linalg.norm(vertices(d + "/deformed.obj") - vertices(last), axis=1) * s
m = np.linalg.norm(vertices(last) - vertices(first), axis=1) * s
print("direct first -> last frame: %.1f s, err mean %.3e p95 %.3e (motion mean %.3e), min det %.3f"
      % (r["result"]["seconds"]["match"], e.mean(), np.percentile(e, 95), m.mean(),
         r["result"]["minJacobian"]))
PY
