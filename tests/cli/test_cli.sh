#!/usr/bin/env bash
# CLI tests of vdb_match: exit codes, error text and output.
# Usage: test_cli.sh VDB_MATCH ASSETS_DIR
# Invalid inputs (a fog volume, a file with two float grids) are written with pyopenvdb into a
# scratch directory; the python interpreter is $VDBMATCH_PYTHON, else the first of
# /usr/bin/python3 and python3 that imports pyopenvdb.
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"

# ---------------------------------------------------------------- invalid inputs
find_python "pyopenvdb"
"$PYTHON" - "$SCRATCH" <<'PY' || { echo "FAIL setup: could not write the invalid inputs"; exit 1; }
import sys
import pyopenvdb as vdb
out = sys.argv[1]
fog = vdb.createLevelSetSphere(radius=1.0, voxelSize=0.1)
fog.gridClass = vdb.GridClass.FOG_VOLUME
fog.name = "density"
vdb.write(out + "/fog.vdb", grids=[fog])
a = vdb.createLevelSetSphere(radius=1.0, voxelSize=0.1)
a.name = "surface"
b = vdb.createLevelSetSphere(radius=0.5, voxelSize=0.1)
b.name = "inner"
vdb.write(out + "/two.vdb", grids=[a, b])
PY
printf 'not a vdb file\n' >"$SCRATCH/text.vdb"
head -c 2000 "$ELLIPSOID" >"$SCRATCH/truncated.vdb"

# ---------------------------------------------------------------- help and version
check help 0 'Exit codes' '' -- --help
check help-energy 0 'energy SOURCE' '' -- energy --help
check version 0 '^vdb_match [0-9]+\.[0-9]+\.[0-9]+' '' -- --version

# ---------------------------------------------------------------- usage errors (1)
check no-arguments 1 '' 'missing arguments' --
check unknown-option 1 '' "unknown option '--bogus'" -- energy "$SPHERE" "$ELLIPSOID" --bogus
check missing-value 1 '' '--level expects a value' -- energy "$SPHERE" "$ELLIPSOID" --level
check bad-number 1 '' "--level expects an integer, got 'abc'" -- energy "$SPHERE" "$ELLIPSOID" --level abc
check bad-real 1 '' "--c-mem expects a finite number, got '1x'" -- energy "$SPHERE" "$ELLIPSOID" --c-mem 1x
check bad-energy 1 '' '--energy expects' -- energy "$SPHERE" "$ELLIPSOID" --energy other
check missing-target 1 '' 'expects SOURCE.vdb TARGET.vdb' -- energy "$SPHERE"
check contradictory 1 '' '--grid cannot be combined' -- energy "$SPHERE" "$ELLIPSOID" --grid surface --source-grid surface

# ---------------------------------------------------------------- I/O errors (2)
check missing-file 2 '' 'does not exist' -- energy "$SCRATCH/nothere.vdb" "$ELLIPSOID" --quiet
check not-vdb 2 '' 'cannot be read as a VDB file' -- energy "$SCRATCH/text.vdb" "$ELLIPSOID" --quiet
check truncated 2 '' '' -- energy "$SPHERE" "$SCRATCH/truncated.vdb" --quiet

# ---------------------------------------------------------------- invalid input (3)
check not-level-set 3 '' "is not a level set \(grid class 'fog volume'\)" -- energy "$SCRATCH/fog.vdb" "$ELLIPSOID" --quiet
check several-grids 3 '' "several float grids \('inner' \(float\), 'surface' \(float\)\)" -- energy "$SCRATCH/two.vdb" "$ELLIPSOID" --quiet
check missing-grid 3 '' "no grid named 'nothere'" -- energy "$SPHERE" "$ELLIPSOID" --grid nothere --quiet
check level-range 3 '' 'level must be in \[1, 8\]' -- energy "$SPHERE" "$ELLIPSOID" --level 0 --quiet
check parameter-range 3 '' 'c_mem must be finite and >= 0' -- energy "$SPHERE" "$ELLIPSOID" --c-mem -1 --quiet
check margin-range 3 '' 'margin must be in' -- energy "$SPHERE" "$ELLIPSOID" --margin 0.5 --quiet

# ---------------------------------------------------------------- success (0)
check energy 0 '^  total +[0-9.]+e[+-][0-9]+$' '' -- energy "$SPHERE" "$ELLIPSOID" --level 4 --quiet
check energy-grids 0 'total' '' -- energy "$SCRATCH/two.vdb" "$SPHERE" --source-grid inner --level 3 --quiet --threads 1
check energy-json 0 '"total": [0-9.]+(e[+-][0-9]+)?,?$' '' -- energy "$SPHERE" "$ELLIPSOID" --level 4 --json --quiet
check energy-directional 0 'directional' '' -- energy "$SPHERE" "$ELLIPSOID" --level 4 --energy=directional --quiet
check energy-identical 0 'match +0\.0+e\+00 +0\.0+e\+00' '' -- energy "$SPHERE" "$SPHERE" --level 4 --quiet
"$VDB_MATCH" energy "$SPHERE" "$ELLIPSOID" --level 4 --json --quiet >"$SCRATCH/json" 2>/dev/null
count=$((count + 1))
if "$PYTHON" -c 'import json, sys; d = json.load(open(sys.argv[1])); assert d["total"] > 0 and len(d["terms"]["match"]) == 2' "$SCRATCH/json"; then
    echo "ok   json-parses"
else
    failures=$((failures + 1))
    echo "FAIL json-parses: --json output is not the expected JSON"
fi

# ---------------------------------------------------------------- interrupted (5)
count=$((count + 1))
"$VDB_MATCH" energy "$SPHERE" "$ELLIPSOID" --level 8 --quiet >"$SCRATCH/out" 2>"$SCRATCH/err" &
pid=$!
# Long enough for the command to install its handler even on a loaded machine (level 8 takes far
# longer than this to evaluate).
sleep 3
kill -INT "$pid" 2>/dev/null
wait "$pid"
code=$?
if [ "$code" -eq 5 ] && grep -q '^vdb_match: error: interrupted$' "$SCRATCH/err"; then
    echo "ok   interrupted"
else
    failures=$((failures + 1))
    echo "FAIL interrupted: exit code $code, expected 5"
    sed 's/^/  stderr: /' "$SCRATCH/err"
fi

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
