#!/usr/bin/env bash
# CLI tests of densities given where a level set is expected: a fog volume, or a float grid with
# every value in [0, 1], is refused with a message naming --iso-value; with --iso-value X, match
# and energy read it as the level set of its iso-surface {density = X}.
# Usage: test_cli_fog.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_fog.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_fog.sh VDB_MATCH ASSETS_DIR}
ELLIPSOID="$ASSETS/ellipsoid.vdb"
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-fog.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"

find_python "pyopenvdb"

# A ball of density: 1 inside, 0 outside, 0.5 at radius 1.5 around (2, 2, 2) (voxel 0.1), as a
# fog volume and as an unclassified float grid; level set spheres of radius 1.5 and 1.2.
"$PYTHON" - "$SCRATCH" <<'PY' || { echo "FAIL setup: could not write the densities"; exit 1; }
import sys
import numpy as np
import pyopenvdb as vdb
out = sys.argv[1]
n = 40
i = np.arange(n) * 0.1
x, y, z = np.meshgrid(i, i, i, indexing="ij")
r = np.sqrt((x - 2) ** 2 + (y - 2) ** 2 + (z - 2) ** 2)
density = np.clip(0.5 + (1.5 - r) / 0.4, 0.0, 1.0).astype(np.float32)
for name, cls in (("fog", vdb.GridClass.FOG_VOLUME), ("unclassified", vdb.GridClass.UNKNOWN)):
    g = vdb.FloatGrid()
    g.copyFromArray(density, ijk=(0, 0, 0))
    g.transform = vdb.createLinearTransform(voxelSize=0.1)
    g.gridClass = cls
    g.name = "density"
    vdb.write(out + "/" + name + ".vdb", grids=[g])
for radius, name in ((1.5, "ball15"), (1.2, "ball12")):
    s = vdb.createLevelSetSphere(radius=radius, center=(2, 2, 2), voxelSize=0.1)
    s.name = "surface"
    vdb.write(out + "/" + name + ".vdb", grids=[s])
PY

# ---------------------------------------------------------------- refused, with what to do (3)
check fog-refused-match 3 '' "is not a level set \(grid class 'fog volume'\): it is a density .*--iso-value X" -- "$SCRATCH/fog.vdb" "$ELLIPSOID" -o "$SCRATCH/o" --quiet
check fog-refused-energy 3 '' "is not a level set \(grid class 'fog volume'\): it is a density .*--iso-value X" -- energy "$SCRATCH/fog.vdb" "$ELLIPSOID" --quiet
check unclassified-refused 3 '' "is not a level set \(grid class 'unknown'\): it is a density .*--iso-value X" -- energy "$SCRATCH/unclassified.vdb" "$ELLIPSOID" --quiet
check iso-out-of-range 3 '' 'has no iso-surface at 2 \(active values in \[.*, 1\]\); choose an iso value between them' -- energy "$SCRATCH/fog.vdb" "$ELLIPSOID" --iso-value 2 --quiet
check iso-no-vdb 1 '' '--iso-value applies to .vdb densities' -- energy "$FIGURE_A" "$FIGURE_B" --iso-value 0.5
check iso-not-a-number 1 '' "--iso-value expects a finite number, got 'half'" -- energy "$SCRATCH/fog.vdb" "$ELLIPSOID" --iso-value half

# ---------------------------------------------------------------- converted (0)
check fog-energy 0 '"format": "density"' '' -- energy "$SCRATCH/fog.vdb" "$SCRATCH/ball15.vdb" --iso-value 0.5 --level 4 --json --quiet
"$VDB_MATCH" energy "$SCRATCH/fog.vdb" "$SCRATCH/ball15.vdb" --iso-value 0.5 --level 5 --json --quiet >"$SCRATCH/same.json" 2>/dev/null
"$VDB_MATCH" energy "$SCRATCH/unclassified.vdb" "$SCRATCH/ball12.vdb" --iso-value 0.5 --level 5 --json --quiet >"$SCRATCH/other.json" 2>/dev/null
count=$((count + 1))
# The iso-surface at 0.5 is the sphere of radius 1.5: its energy against that sphere is a small
# fraction of the energy against the sphere of radius 1.2.
if "$PYTHON" - "$SCRATCH/same.json" "$SCRATCH/other.json" <<'PY'; then
import json, sys
same = json.load(open(sys.argv[1]))
other = json.load(open(sys.argv[2]))
assert same["source"]["isoValue"] == 0.5 and same["source"]["format"] == "density"
assert other["source"]["format"] == "density" and other["target"]["format"] == "level set"
ms = sum(same["terms"]["match"])
mo = sum(other["terms"]["match"])
assert ms < 0.02 * mo, (ms, mo)
PY
    echo "ok   iso-surface-is-the-ball"
else
    fail "iso-surface-is-the-ball: the iso-surface at 0.5 is not the sphere of radius 1.5"
fi
check fog-match 0 'converged|not converged' '' -- "$SCRATCH/fog.vdb" "$SCRATCH/ball12.vdb" -o "$SCRATCH/m" --iso-value 0.5 --levels 3..3 --quiet --no-inverse --no-jacobian
count=$((count + 1))
if "$PYTHON" -c 'import json, sys; r = json.load(open(sys.argv[1])); assert r["source"]["format"] == "density" and r["source"]["isoValue"] == 0.5 and r["target"]["format"] == "level set"' "$SCRATCH/m/report.json"; then
    echo "ok   fog-match-report"
else
    fail "fog-match-report: report.json does not record the density"
fi
check iso-ignores-level-sets 0 'total' '' -- energy "$SCRATCH/ball15.vdb" "$ELLIPSOID" --iso-value 0.5 --level 4 --quiet

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
