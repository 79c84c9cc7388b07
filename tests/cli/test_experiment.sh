#!/usr/bin/env bash
# The paper's experiment script (tools/run_experiment.py) in its reduced form: both energies,
# both directions, both bundled pairs at coarse levels; checks that results.md has the
# tab:inverseError table with finite numbers and that the pictures were written.
# Usage: test_experiment.sh VDB_MATCH SOURCE_DIR
set -euo pipefail
VDB_MATCH=${1:?usage: test_experiment.sh VDB_MATCH SOURCE_DIR}
SOURCE_DIR=${2:?usage: test_experiment.sh VDB_MATCH SOURCE_DIR}
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-experiment.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT
PYTHON=python3
[ -x /usr/bin/python3 ] && PYTHON=/usr/bin/python3
"$PYTHON" "$SOURCE_DIR/tools/run_experiment.py" --quick --vdb-match "$VDB_MATCH" \
    --work "$SCRATCH/work" --output "$SCRATCH/docs/results.md" >"$SCRATCH/log" 2>&1 ||
    { tail -20 "$SCRATCH/log"; echo "FAIL run_experiment.py"; exit 1; }
md="$SCRATCH/docs/results.md"
fail=0
for c in "S, dir" "S, sym" "J, dir" "J, sym"; do
    line=$(grep -F "| $c (" "$md" || true)
    if [ -z "$line" ]; then echo "FAIL no row for $c"; fail=1; continue; fi
    # Four finite numbers after the levels column.
    n=$(echo "$line" | awk -F'|' '{for (i = 4; i <= 7; ++i) if ($i ~ /^ *[0-9.]+(e[-+]?[0-9]+)? *$/) c++; print c + 0}')
    if [ "$n" -ne 4 ]; then echo "FAIL row '$c' has $n numeric columns: $line"; fail=1; else echo "ok   $c"; fi
done
pngs=$(ls "$SCRATCH/docs/results"/*.png 2>/dev/null | wc -l)
if [ "$pngs" -lt 8 ]; then echo "FAIL only $pngs pictures"; fail=1; else echo "ok   $pngs pictures"; fi
exit $fail
