#!/usr/bin/env bash
# CLI tests of `vdb_match [match] SOURCE TARGET -o OUTDIR`: usage and input errors with their
# exit codes, end-to-end runs at coarse levels (3D level sets, 2D polylines) whose outputs are
# read back with vdb_print and pyopenvdb, and Ctrl-C writing partial outputs marked interrupted.
# Usage: test_cli_match.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_match.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_match.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-match.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"


find_python "pyopenvdb"

# Invalid inputs.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$SCRATCH/open.obj"
printf '0 0\n1 0\nnan 1\n' >"$SCRATCH/nan.polyline"
printf 'solid x\nendsolid x\n' >"$SCRATCH/empty.stl"
printf 'hello\n' >"$SCRATCH/shape.xyz"
touch "$SCRATCH/afile"

# ---------------------------------------------------------------- usage (1)
check help 0 'SOURCE TARGET -o OUTDIR' '' -- --help
check missing-output 1 '' 'missing the output directory' -- "$SPHERE" "$ELLIPSOID"
check one-input 1 '' 'expected SOURCE TARGET' -- "$SPHERE" -o "$SCRATCH/o"
check levels-order 1 '' 'finer than the last' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --levels 6..4
check levels-syntax 1 '' '--levels expects A..B' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --levels 6
check grid-mesh 1 '' '--grid applies to .vdb inputs' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --grid surface
check bad-energy 1 '' '--energy expects' -- match "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --energy x

# ---------------------------------------------------------------- I/O (2)
check missing-file 2 '' 'does not exist' -- "$SCRATCH/nothere.vdb" "$ELLIPSOID" -o "$SCRATCH/o" --quiet
check outdir-is-file 2 '' 'output directory' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/afile" --levels 3..3 --quiet

# ---------------------------------------------------------------- invalid input (3)
check open-mesh 3 '' 'open' -- "$SCRATCH/open.obj" "$SPHERE" -o "$SCRATCH/o" --quiet
check nan-polyline 3 '' '' -- "$SCRATCH/nan.polyline" "$FIGURE_B" -o "$SCRATCH/o" --quiet
check empty-stl 3 '' '' -- "$SCRATCH/empty.stl" "$SPHERE" -o "$SCRATCH/o" --quiet
check unknown-type 3 '' 'unknown file type' -- "$SCRATCH/shape.xyz" "$SPHERE" -o "$SCRATCH/o" --quiet
check dimension-mismatch 3 '' '2D shape but' -- "$FIGURE_A" "$SPHERE" -o "$SCRATCH/o" --quiet
check margin-range 3 '' 'margin' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --margin 0.7 --quiet
check parameter-range 3 '' 'c_mem' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --c-mem -1 --quiet
# Resource-exhausting or meaningless options are refused before anything large is allocated.
check levels-too-fine 3 '' 'finest level is at most 9 in 3D' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --levels 12..12 --quiet
check levels-0-20 3 '' 'levels must be in' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --levels 0..20 --quiet
check threads-huge 1 '' 'threads must be in 0..1024' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --threads 2147483647 --quiet
check threads-10000 1 '' 'threads must be in 0..1024' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --threads 10000 --quiet
check metric-tolerance 3 '' 'metric tolerance must be in' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --metric-tolerance -1 --quiet
check q-range 3 '' 'q must be in \[0, 8\]' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --q -1000 --quiet
check refine-margin-range 3 '' 'refinementMarginCells must be in' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --refine-margin 1e9 --quiet
check c-match-range 3 '' 'c_match must be in' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --c-match 1e300 --quiet
[ -e "$SCRATCH/o/deformation.vdb" ] && fail "an input error left outputs in $SCRATCH/o"

# ---------------------------------------------------------------- 3D end to end (0)
check match-3d 0 'converged|not converged' 'level 5 done' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3" --levels 3..5
check inner-distance-level-3d 3 '' 'innerDistanceLevel is at most 8 in 3D' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --inner-distance-level 9 --quiet
count=$((count + 1))
if command -v vdb_print >/dev/null 2>&1; then
    # (captured first: grep -q closing the pipe early would fail the pipeline under pipefail)
    listing=$(vdb_print -l "$SCRATCH/m3/deformation.vdb" 2>&1; vdb_print -l "$SCRATCH/m3/deformed.vdb" 2>&1)
    if grep -q 'Name: displacement' <<<"$listing" && grep -q 'vec3s' <<<"$listing" &&
        grep -q 'Name: surface' <<<"$listing" && grep -qi 'class: level set' <<<"$listing"; then
        echo "ok   vdb_print"
    else
        fail "vdb_print: cannot list the outputs"
    fi
else
    echo "ok   vdb_print (skipped: not installed)"
fi
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/m3" 3 <<'PY'; then echo "ok   readback-3d"; else fail "readback-3d"; fi
import json, math, sys
import pyopenvdb as vdb
out, dim = sys.argv[1], int(sys.argv[2])
g = vdb.read(out + "/deformation.vdb", "displacement")
assert g.valueTypeName == "vec3s", g.valueTypeName
assert g.vectorType == vdb.VectorType.CONTRAVARIANT_RELATIVE if hasattr(vdb, "VectorType") else True
meta = g.metadata
for key in ("vdbmatch_version", "vdbmatch_command", "vdbmatch_energy", "vdbmatch_energy_total",
            "vdbmatch_residual_mean", "is_interrupted"):
    assert key in meta, key
assert meta["is_interrupted"] is False
n = 0
for item in g.citerOnValues():
    v = item.value
    assert all(math.isfinite(c) for c in v), v
    n += 1
assert n > 0
s = vdb.read(out + "/deformed.vdb", "surface")
assert s.gridClass == vdb.GridClass.LEVEL_SET, s.gridClass
r = json.load(open(out + "/report.json"))
assert r["dimension"] == dim and r["status"] in ("converged", "not converged")
# The automatic anchors' count is per dimension: 300 in 3D (100 in 2D, below).
assert r["parameters"]["anchorCount"] == 300, r["parameters"]
last = r["levels"][-1]
assert r["result"]["residual"]["meanUnit"] < last["h"] / 2, (r["result"]["residual"], last["h"])
assert r["result"]["minJacobian"] > 0
assert last["unknowns"] > 0 and last["nodes"] <= last["denseNodes"]
assert len(r["levels"]) == r["parameters"]["maxLevel"] - r["parameters"]["minLevel"] + 1
obj = open(out + "/deformed.obj").read()
assert obj.count("\nv ") > 100
# The exact inverse and the Jacobian, next to the deformation (docs/apply.md).
assert r["outputs"] == ["deformation.vdb", "inverse.vdb", "jacobian.vdb", "deformed.vdb",
                        "deformed.obj", "report.json"], r["outputs"]
inv = vdb.read(out + "/inverse.vdb", "displacement")
assert inv.metadata["is_inverse"] is True and not meta.get("is_inverse", False)
assert inv.activeVoxelCount() == g.activeVoxelCount()
assert max(abs(a - b) for a, b in zip(inv.transform.indexToWorld((3, 4, 5)),
                                     g.transform.indexToWorld((3, 4, 5)))) < 1e-12
assert r["inverse"]["failures"] == 0 and r["inverse"]["maxResidualWorld"] < 1e-9
jac = vdb.read(out + "/jacobian.vdb", "det_jacobian")
lo, hi = jac.evalMinMax()
assert abs(jac.metadata["vdbmatch_det_min"] - r["result"]["minJacobian"]) < 1e-4, (jac.metadata, r["result"])
# cell means (stored as float) lie between the simplex extremes
assert jac.metadata["vdbmatch_det_min"] - 1e-6 <= lo <= 1.0 <= hi <= jac.metadata["vdbmatch_det_max"] + 1e-6, (lo, hi)
PY
ls -A "$SCRATCH/m3" | grep -q "\.tmp" && fail "temporary files left in the output directory"

# ---------------------------------------------------------------- identical shapes: phi = Id, converged at once
check identical-shapes 0 '^vdb_match: converged; .*min det 1,' '' -- "$SPHERE" "$SPHERE" -o "$SCRATCH/same" --levels 3..4 --quiet

# ---------------------------------------------------------------- a small piece beside a shape: warned before the run, in the report
# figure_b (length 8.56) and a square of side 0.02 (0.9% of it) away from its box (x <= 0.6602,
# y <= 0.8950): the gap between the boxes is |(1.5 - 0.6602, 1.5 - 0.8950)| = 1.0350.
{ grep -v '^#' "$FIGURE_B"; printf '\n1.5 1.5\n1.52 1.5\n1.52 1.52\n1.5 1.52\n'; } >"$SCRATCH/fragment.polyline"
check small-piece-warned 0 'converged' 'warning: the target has 2 pieces, 1 of them small \(4 vertices, 0\.9[0-9]% of its length\), up to 1\.0[34] world units .* away from the largest' -- "$FIGURE_A" "$SCRATCH/fragment.polyline" -o "$SCRATCH/frag" --levels 4..4 --quiet
grep -q 'pieces' "$SCRATCH/err" && grep -q 'source has' "$SCRATCH/err" && fail "small-piece-warned: the source (one piece) was warned about"
if "$PYTHON" - "$SCRATCH/frag/report.json" <<'PY'; then echo "ok   small-piece-report"; else fail "small-piece-report"; fi
import json, sys
r = json.load(open(sys.argv[1]))
assert r["source"]["pieces"] == 1 and r["source"]["smallPieces"]["count"] == 0, r["source"]
t = r["target"]
assert t["pieces"] == 2 and t["smallPieces"]["count"] == 1 and t["smallPieces"]["vertices"] == 4, t
assert abs(t["smallPieces"]["share"] - 0.08 / (8.5635 + 0.08)) < 1e-4, t
assert abs(t["smallPieces"]["farthest"] - 1.0350) < 1e-3, t
PY
# The same for a level set: a cube of side 2 and one of side 0.16 beside it (0.6% of the area), in
# one grid, as a modeller's VDB with a floater; its zero level set is meshed in two pieces.
"$PYTHON" - "$SCRATCH/floater.vdb" <<'PY'
import sys, numpy as np, pyopenvdb as vdb
def cube(lo, side):
    p = [[lo[0] + side * (k & 1), lo[1] + side * ((k >> 1) & 1), lo[2] + side * ((k >> 2) & 1)] for k in range(8)]
    q = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return np.array(p, float), np.array([t for a, b, c, d in q for t in ((a, b, c), (a, c, d))])
p1, t1 = cube((-1, -1, -1), 2.0)
p2, t2 = cube((1.5, -0.08, -0.08), 0.16)
g = vdb.FloatGrid.createLevelSetFromPolygons(np.vstack([p1, p2]), triangles=np.vstack([t1, t2 + 8]).astype(np.int32),
                                             transform=vdb.createLinearTransform(voxelSize=0.04), halfWidth=3.0)
g.name = "surface"
vdb.write(sys.argv[1], grids=[g])
PY
check small-piece-level-set 0 'converged' 'warning: the target has 2 pieces, 1 of them small \([0-9]+ vertices, 0\.[0-9]+% of its area\), up to 0\.[45][0-9]* world units' -- "$SPHERE" "$SCRATCH/floater.vdb" -o "$SCRATCH/floater" --levels 3..4 --quiet
# One piece each: no warning.
check one-piece-no-warning 0 'converged' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/nofrag" --levels 4..4 --quiet
grep -q 'pieces' "$SCRATCH/err" && fail "one-piece-no-warning: warned about pieces"

# ---------------------------------------------------------------- --config: report.json reproduces its run
check config-reproduces 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3c" --config "$SCRATCH/m3/report.json" --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/m3/report.json" "$SCRATCH/m3c/report.json" <<'PY'; then echo "ok   config-same-result"; else fail "config-same-result"; fi
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a["parameters"] == b["parameters"], (a["parameters"], b["parameters"])
assert a["result"]["energy"] == b["result"]["energy"], (a["result"]["energy"], b["result"]["energy"])
PY
printf '{"cMatch": 2, "minLevel": 3, "maxLevel": 3}\n' >"$SCRATCH/params.json"
printf '{"cMatch": 2, "levelz": 3}\n' >"$SCRATCH/typo.json"
printf '{"cMatch": "x"}\n' >"$SCRATCH/badvalue.json"
printf '[1, 2]\n' >"$SCRATCH/array.json"
check config-overridden 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3o" --config "$SCRATCH/params.json" --c-match 3 --quiet
count=$((count + 1))
if grep -q '"cMatch": 3' "$SCRATCH/m3o/report.json" && grep -q '"maxLevel": 3' "$SCRATCH/m3o/report.json"; then
    echo "ok   config-command-line-wins"
else
    fail "config-command-line-wins"
fi
# A report.json of a version before the surface test (no surfaceTolerance) reproduces its run
# with the test off, one before the coarse membrane factor with one c_mem, and one before the
# second path with one path, whatever today's defaults.
"$PYTHON" - "$SCRATCH/m3/report.json" "$SCRATCH/old_report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for k in ("surfaceTolerance", "surfaceLevels", "surfaceFromLevel", "coarseMembraneFactor",
          "membraneSaturation", "secondPath"):
    r["parameters"].pop(k, None)
json.dump(r, open(sys.argv[2], "w"))
PY
check config-old-report 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3old" --config "$SCRATCH/old_report.json" --levels 3..3 --quiet
count=$((count + 1))
if "$PYTHON" -c 'import json, sys; p = json.load(open(sys.argv[1]))["parameters"]; sys.exit(0 if p["surfaceTolerance"] == 0 and p["coarseMembraneFactor"] == 1 and p["surfaceFromLevel"] == 0 and p["membraneSaturation"] == 0 and p["secondPath"] == "off" else 1)' "$SCRATCH/m3old/report.json"; then
    echo "ok   config-old-report-surface-off"
else
    fail "config-old-report-surface-off"
fi
# ... and one with the surface test but before surfaceFromLevel keeps it at the last level only.
"$PYTHON" - "$SCRATCH/m3/report.json" "$SCRATCH/old_report2.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
r["parameters"].pop("surfaceFromLevel")
json.dump(r, open(sys.argv[2], "w"))
PY
check config-old-report-from-level 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3old2" --config "$SCRATCH/old_report2.json" --levels 3..3 --quiet
count=$((count + 1))
if "$PYTHON" -c 'import json, sys; p = json.load(open(sys.argv[1]))["parameters"]; sys.exit(0 if p["surfaceFromLevel"] == 0 and p["surfaceTolerance"] > 0 else 1)' "$SCRATCH/m3old2/report.json"; then
    echo "ok   config-old-report-from-level-off"
else
    fail "config-old-report-from-level-off"
fi
check surface-from-level-negative 3 '' 'surfaceFromLevel must be >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --surface-from-level -1 --quiet
check config-unknown-key 3 '' "unknown key 'levelz'" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --config "$SCRATCH/typo.json" --quiet
check config-bad-value 1 '' "key 'cMatch': --c-match expects a finite number" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --config "$SCRATCH/badvalue.json" --quiet
check config-not-object 3 '' 'not a JSON object' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --config "$SCRATCH/array.json" --quiet
check config-missing 2 '' 'cannot read' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --config "$SCRATCH/none.json" --quiet

# ---------------------------------------------------------------- 2D end to end (0)
if [ -f "$FIGURE_A" ] && [ -f "$FIGURE_B" ]; then
    check match-2d 0 'converged|not converged' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2" --levels 4..6 --quiet
    count=$((count + 1))
    if "$PYTHON" - "$SCRATCH/m2" 2 <<'PY'; then echo "ok   readback-2d"; else fail "readback-2d"; fi
import json, sys
import pyopenvdb as vdb
out = sys.argv[1]
g = vdb.read(out + "/deformation.vdb", "displacement")
lo, hi = g.evalActiveVoxelBoundingBox()
assert lo[2] == hi[2] == 0, (lo, hi)
r = json.load(open(out + "/report.json"))
assert r["dimension"] == 2
assert r["result"]["residual"]["meanUnit"] < r["levels"][-1]["h"] / 2
PY
    # --half, --no-inverse, --log-jacobian: smaller files, no inverse, the log grid.
    check match-2d-half 0 'deformed.obj' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2h" --levels 4..6 --quiet --half --no-inverse --log-jacobian
    count=$((count + 1))
    if "$PYTHON" - "$SCRATCH/m2" "$SCRATCH/m2h" <<'PY'; then echo "ok   half-and-options"; else fail "half-and-options"; fi
import json, os, sys
import pyopenvdb as vdb
full, half = sys.argv[1], sys.argv[2]
assert not os.path.exists(half + "/inverse.vdb")
r = json.load(open(half + "/report.json"))
assert r["half"] is True and "inverse.vdb" not in r["outputs"] and "inverse" not in r
assert os.path.getsize(half + "/deformation.vdb") < 0.8 * os.path.getsize(full + "/deformation.vdb")
a = vdb.read(full + "/deformation.vdb", "displacement")
b = vdb.read(half + "/deformation.vdb", "displacement").getConstAccessor()
worst = max(max(abs(x - y) for x, y in zip(it.value, b.getValue(it.min))) for it in a.citerOnValues())
h = a.transform.voxelSize()[0]
assert worst < 1e-2 * h, (worst, h)
lj = vdb.read(half + "/jacobian.vdb", "log_det_jacobian")
lo, hi = lj.evalMinMax()
assert lo < 0 < hi, (lo, hi)
PY
fi

# ---------------------------------------------------------------- --preset paper: the paper's experiment
check preset-unknown 1 '' "--preset expects 'default' or 'paper'" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --preset fast --quiet
check preset-paper 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/pp" --levels 3..4 --preset paper --quiet
check preset-paper-override 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/ppo" --levels 3..4 --surface-tolerance 0.05 --preset paper --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/pp" "$SCRATCH/ppo" "$SCRATCH/m3" <<'PY'; then echo "ok   preset-report"; else fail "preset-report"; fi
import json, sys
paper, override, default = (json.load(open(d + "/report.json"))["parameters"] for d in sys.argv[1:])
assert paper["preset"] == "paper" and paper["surfaceTolerance"] == 0, paper
assert override["preset"] == "paper" and override["surfaceTolerance"] == 0.05, override
assert default["preset"] == "default" and default["surfaceTolerance"] > 0, default
# tab:parameters (3D): c_match 4.096, c_vol 0.8, c_mem 1, c_bend 0.2, q 4, theta 1
assert (paper["cMatch"], paper["cVol"], paper["cMem"], paper["cBend"], paper["q"], paper["theta"]) == (4.096, 0.8, 1, 0.2, 4, 1), paper
# the paper has one c_mem; the default stiffens the membrane below the finest level (an addition)
assert paper["coarseMembraneFactor"] == 1 and default["coarseMembraneFactor"] == 3, (paper, default)
assert default["cMem"] == 1, default
# the paper's membrane density; the default saturates it at the first two levels (an addition)
assert paper["membraneSaturation"] == 0, paper
assert default["membraneSaturation"] == 0.1 and default["membraneSaturationLevels"] == 2, default
# the descent's metric weight (the paper gives none): sigma^2 / 2 in 3D and in the paper's preset
assert paper["metricTauFactor"] == 0.5 and default["metricTauFactor"] == 0.5, (paper, default)
# the Hessian smoothed from each shape's noise (an addition): off in the paper's preset
assert paper["noiseSmoothing"] == 0 and default["noiseSmoothing"] > 0, (paper, default)
reports = [json.load(open(d + "/report.json")) for d in sys.argv[1:]]
assert "noise" not in reports[0], reports[0].keys()
noise = reports[2]["noise"]
assert 0 < noise["source"] < 1e-3 and 0 < noise["target"] < 1e-3, noise
# ... and, in 3D, from the noise a lattice of h = 1/128 sees (an addition): the length is the
# larger of the two readings' (these noise-free level sets read ~1e-4 on the lattice)
assert paper["latticeNoiseSmoothing"] == 0 and default["latticeNoiseSmoothing"] == 3.5, (paper, default)
assert paper["anchorNoiseTolerance"] == 0 and default["anchorNoiseTolerance"] == 1.6, (paper, default)
# the anchors beside given landmarks (an addition): off in the paper's preset
assert paper["landmarkAnchors"] == "off" and default["landmarkAnchors"] == "on", (paper, default)
# the rigid limbs (an addition): off in the paper's preset, 10^4 in 3D
assert paper["rigidLimbWeight"] == 0 and default["rigidLimbWeight"] == 1e4, (paper, default)
assert default["rigidLimbMinMotion"] == 1 and default["rigidLimbCount"] == 20 and default["rigidLimbReach"] == 0.6, default
# the rigid segments (an addition): off in 3D (these are 3D runs), read back by --config
assert default["rigidSegment"] == "off" and default["rigidSegmentMinAngle"] == 10 and default["rigidSegmentTipMotion"] == 0.03, default
assert all(0 < v < 1e-3 for v in noise["lattice"]), noise
for i, shape in enumerate(("source", "target")):
    assert noise["smoothingLength"][i] == max(default["noiseSmoothing"] * noise[shape],
                                              default["latticeNoiseSmoothing"] * noise["lattice"][i]), noise
# the bending weight lowered where the noise smoothing acts (an addition): off in the paper's
# preset; these noise-free level sets get no pass, so every level keeps the paper's c_bend
assert paper["noiseBending"] == 0 and default["noiseBending"] == 4, (paper, default)
for r in reports:
    assert [l["bendingFactor"] for l in r["levels"]] == [1] * len(r["levels"]), r["levels"]
PY
check noise-smoothing-negative 1 '' '--noise-smoothing must be a finite number >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --noise-smoothing -1 --quiet
check lattice-noise-smoothing-negative 1 '' '--lattice-noise-smoothing must be a finite number >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --lattice-noise-smoothing -1 --quiet
check noise-bending-negative 1 '' '--noise-bending must be a finite number >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --noise-bending -1 --quiet
check anchor-noise-tolerance-negative 1 '' '--anchor-noise-tolerance must be a finite number >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --anchor-noise-tolerance -1 --quiet
check iteration-coarsening-below-one 1 '' '--iteration-coarsening must be a finite number >= 1' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --iteration-coarsening 0.5 --quiet
# A report of a version before an addition reproduces its run without it:
# old_report NAME KEY ASSERTION drops parameters.KEY from the 3D report, reruns it with --config
# and checks ASSERTION (Python, with r the new report and p its parameters).
old_report() {
    "$PYTHON" -c 'import json, sys; r = json.load(open(sys.argv[1])); r["parameters"].pop(sys.argv[3]); json.dump(r, open(sys.argv[2], "w"))' "$SCRATCH/m3/report.json" "$SCRATCH/old_$1.json" "$2"
    check "$1-old-config" 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/old_$1" --config "$SCRATCH/old_$1.json" --levels 3..3 --quiet
    count=$((count + 1))
    if "$PYTHON" -c 'import json, sys; r = json.load(open(sys.argv[1])); p = r["parameters"]; exec("assert " + sys.argv[2])' "$SCRATCH/old_$1/report.json" "$3"; then echo "ok   $1-old-report"; else fail "$1-old-report"; fi
}
# ... the noise smoothing: without it;
old_report noise-smoothing noiseSmoothing 'p["noiseSmoothing"] == 0 and "noise" not in r'
# ... the noise-adaptive bending weight: without it;
old_report noise-bending noiseBending 'p["noiseBending"] == 0 and p["noiseSmoothing"] > 0, p'
# ... the lattice reading of the noise: with the vertex reading alone;
old_report lattice-noise latticeNoiseSmoothing 'p["latticeNoiseSmoothing"] == 0 and r["noise"]["lattice"] == [0, 0] and r["noise"]["smoothingLength"][1] == p["noiseSmoothing"] * r["noise"]["target"], r'
# ... the anchors' tolerance following the noise: with the fixed tolerance;
old_report anchor-noise anchorNoiseTolerance 'p["anchorNoiseTolerance"] == 0 and p["latticeNoiseSmoothing"] == 3.5, p'
# ... the anchors beside given landmarks: without them.
old_report landmark-anchors landmarkAnchors 'p["landmarkAnchors"] == "off" and p["autoAnchors"] == "on", p'
# ... the rigid limbs: without them.
old_report rigid-limbs rigidLimbWeight 'p["rigidLimbWeight"] == 0 and p["autoAnchors"] == "on", p'
check membrane-saturation-range 3 '' 'membrane saturation must be in \[0, ' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --membrane-saturation -0.1 --quiet
check membrane-saturation-number 1 '' "--membrane-saturation expects a finite number" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --membrane-saturation nan --quiet
check membrane-saturation-levels-range 3 '' 'membraneSaturationLevels must be >= 0' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --membrane-saturation-levels -1 --quiet
check membrane-saturation-levels-integer 1 '' "--membrane-saturation-levels expects an integer" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --membrane-saturation-levels 1.5 --quiet
# 2D keeps the paper's membrane density by default (the saturation is the 3D default).
check membrane-saturation-2d-default 0 'converged|not converged' '' -- "$ASSETS/figure_a.polyline" "$ASSETS/figure_b.polyline" -o "$SCRATCH/ms2" --levels 4..4 --quiet
# 2D: the metric weight 2 sigma^2 by default, sigma^2 / 2 with --preset paper, X with --metric-tau X.
check metric-tau-2d-paper 0 'converged|not converged' '' -- "$ASSETS/figure_a.polyline" "$ASSETS/figure_b.polyline" -o "$SCRATCH/mt2p" --levels 4..4 --preset paper --quiet
check metric-tau-2d-given 0 'converged|not converged' '' -- "$ASSETS/figure_a.polyline" "$ASSETS/figure_b.polyline" -o "$SCRATCH/mt2g" --levels 4..4 --metric-tau 0.5 --quiet
check metric-tau-negative 3 '' 'metricTauFactor must be finite and >= 0' -- "$ASSETS/figure_a.polyline" "$ASSETS/figure_b.polyline" -o "$SCRATCH/o" --metric-tau -1 --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/ms2" "$SCRATCH/mt2p" "$SCRATCH/mt2g" <<'PY'; then echo "ok   2d-default-report"; else fail "2d-default-report"; fi
import json, sys
reports = [json.load(open(d + "/report.json")) for d in sys.argv[1:]]
default, paper, given = (r["parameters"] for r in reports)
assert default["membraneSaturation"] == 0, default
# the lattice reading of the noise is a 3D default: a 2D run has the vertex reading alone
assert default["latticeNoiseSmoothing"] == 0 and reports[0]["noise"]["lattice"] == [0, 0], reports[0]
assert default["metricTauFactor"] == 2 and paper["metricTauFactor"] == 0.5 and given["metricTauFactor"] == 0.5, (default, paper, given)
# the metric changes the path, not the energy: the same energy at the identity, another end
e = [r["levels"][0] for r in reports]
assert e[0]["initialEnergy"] == e[2]["initialEnergy"], e
assert e[0]["energy"] != e[2]["energy"], e
PY
# Refining an earlier result (--init) saturates no level that run did not: the first two levels
# of --levels are counted, not the first level this run starts at. Level 5 of 3..5, started from
# a 3..4 result, uses the paper's density: its energies equal those of --membrane-saturation 0.
check membrane-saturation-init-base 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/msi" --levels 3..4 --quiet
check membrane-saturation-init 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/msi5" --levels 3..5 --init "$SCRATCH/msi/deformation.vdb" --quiet
check membrane-saturation-init-paper 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/msi5p" --levels 3..5 --init "$SCRATCH/msi/deformation.vdb" --membrane-saturation 0 --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/msi5" "$SCRATCH/msi5p" <<'PY'; then echo "ok   membrane-saturation-init-unsaturated"; else fail "membrane-saturation-init-unsaturated"; fi
import json, sys
a, b = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
assert [l["level"] for l in a["levels"]] == [5], a["levels"]
assert a["parameters"]["membraneSaturation"] == 0.1, a["parameters"]
assert a["levels"][0]["initialEnergy"] == b["levels"][0]["initialEnergy"], (a["levels"][0], b["levels"][0])
assert a["levels"][0]["energy"] == b["levels"][0]["energy"], (a["levels"][0], b["levels"][0])
PY
# The saturation is in the deformation's metadata, as the other coefficients.
check membrane-saturation-run 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/ms" --levels 3..4 --membrane-saturation 0.05 --membrane-saturation-levels 1 --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/ms" <<'PY'; then echo "ok   membrane-saturation-recorded"; else fail "membrane-saturation-recorded"; fi
import json, sys
p = json.load(open(sys.argv[1] + "/report.json"))["parameters"]
assert p["membraneSaturation"] == 0.05 and p["membraneSaturationLevels"] == 1, p
import pyopenvdb
grids = pyopenvdb.readAllGridMetadata(sys.argv[1] + "/deformation.vdb")
m = grids[0]
assert abs(m["vdbmatch_membrane_saturation"] - 0.05) < 1e-15, dict(m)
assert m["vdbmatch_membrane_saturation_levels"] == 1, dict(m)
PY
check coarse-membrane-factor-range 3 '' 'coarseMembraneFactor must be finite' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --coarse-membrane-factor -1 --quiet
check coarse-membrane-factor-number 1 '' "--coarse-membrane-factor expects a finite number" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --coarse-membrane-factor x --quiet
# The coarse volume factor and the second path (additions to the paper): ranges, defaults, the
# report. A run that reaches its target reports why no second path ran; one step per level
# (levels 4..6) leaves the figure's arms behind, and the second path runs.
check coarse-volume-factor-range 3 '' 'coarseVolumeFactor must be finite' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --coarse-volume-factor -1 --quiet
# The coarse sigma factor (an addition to the paper): range, report, metadata, per-level sigma.
check coarse-sigma-factor-range 3 '' 'coarseSigmaFactor must be in \[0.5, 3\]' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --coarse-sigma-factor 4 --quiet
check coarse-sigma-factor 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/csf" --levels 3..4 --coarse-sigma-factor 1.5 --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/csf" "$SCRATCH/m3" <<'PY'; then echo "ok   coarse-sigma-factor-report"; else fail "coarse-sigma-factor-report"; fi
import json, sys
wide, default = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
assert wide["parameters"]["coarseSigmaFactor"] == 1.5 and default["parameters"]["coarseSigmaFactor"] == 1
assert [(l["level"], l["sigma"]) for l in wide["levels"]] == [(3, 3 / 8), (4, 2 / 16)], wide["levels"]
assert all(l["sigma"] == 2 * l["h"] for l in default["levels"]), default["levels"]
import pyopenvdb
assert pyopenvdb.readAllGridMetadata(sys.argv[1] + "/deformation.vdb")[0]["vdbmatch_coarse_sigma_factor"] == 1.5
PY
check second-path-value 1 '' "--second-path expects 'on' or 'off', got 'maybe'" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --second-path maybe --quiet
check second-path-share-range 3 '' 'secondPathShare must be in \[0, 1\]' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --second-path-share 2 --quiet
# (With the 2D default metric weight, one step per level reaches M2; the lighter one of 3D does
# not. The inner-distance term of the 2D default, too, lets one step reach it: off here.)
FIG=("$ASSETS/figure_a.polyline" "$ASSETS/figure_b.polyline" --levels 4..6 --max-iterations 1 --metric-tau 0.5 --inner-distance-weight 0 --no-inverse --no-jacobian)
check second-path-run 0 'second path: .*% of M1 ended farther than sigma from M2 on the first path; energies .* kept path [123] of [23]' '' -- "${FIG[@]}" -o "$SCRATCH/sp"
check second-path-off 0 'converged|not converged' '' -- "${FIG[@]}" -o "$SCRATCH/spoff" --second-path off --quiet
check second-path-factor 0 'converged|not converged' '' -- "${FIG[@]}" -o "$SCRATCH/spcvf" --second-path off --coarse-volume-factor 4 --quiet
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/sp" "$SCRATCH/spoff" "$SCRATCH/spcvf" "$SCRATCH/m3" "$SCRATCH/pp" <<'PY'; then echo "ok   second-path-report"; else fail "second-path-report"; fi
import json, sys
both, first, second, default, paper = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
assert default["parameters"]["secondPath"] == "on" and paper["parameters"]["secondPath"] == "off", paper["parameters"]
assert default["parameters"]["coarseVolumeFactor"] == 1 and default["parameters"]["secondPathShare"] == 0.01
assert default["secondPath"]["ran"] is False and "reached M2" in default["secondPath"]["reason"], default["secondPath"]
assert "secondPath" not in paper and "secondPath" not in first
sp = both["secondPath"]
assert sp["ran"] and sp["farShare"] > 0.01, sp
paths = sp["paths"]
assert 2 <= len(paths) <= 3 and [p["coarseVolumeFactor"] for p in paths] == [1, 4, 16][:len(paths)], paths
# the first path is the run without it, the second the run with 4x the coarse volume weight
assert paths[0]["energy"] == first["result"]["energy"], (paths[0], first["result"])
assert paths[1]["energy"] == second["result"]["energy"], (paths[1], second["result"])
assert paths[0]["farShare"] == first["result"]["residual"]["farShare"] == sp["farShare"]
assert all(p["farShare"] > 0.01 for p in paths[:-1]), paths  # a further path only after a miss
energies = [p["energy"] for p in paths]
assert sp["kept"] == energies.index(min(energies)), sp
assert both["result"]["energy"] == min(energies), both["result"]
for k, p in enumerate(paths):
    if k == sp["kept"]:
        assert p["levels"] is None, p
    else:
        assert [l["level"] for l in p["levels"]] == [4, 5, 6] and p["levels"][-1]["energy"] == p["energy"], p
assert [l["level"] for l in both["levels"]] == [4, 5, 6]
assert both["result"]["residual"]["farShare"] == paths[sp["kept"]]["farShare"]
if sp["kept"] < 2:
    kept = first if sp["kept"] == 0 else second
    assert both["result"]["residual"] == kept["result"]["residual"], (both["result"], kept["result"])
PY
# The target residual (dist(y, phi(M1)) over M2's vertices) and --second-path-target.
check second-path-target-value 1 '' "--second-path-target expects 'on' or 'off', got 'maybe'" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --second-path-target maybe --quiet
check second-path-target-alone 3 '' 'second-path-target on needs --second-path on' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --preset paper --second-path-target on --quiet
check target-residual-line 0 'target residual \(distance of M2.s vertices to phi\(M1\)\): mean .* max .*, 0\.0% of M2 farther than sigma' '' -- "${FIG[@]:0:2}" -o "$SCRATCH/tr" --levels 4..6 --quiet
# No descent step: phi = Id leaves M2 where it is, and stderr says so (also with --quiet).
check target-residual-warning 0 'target residual .* of M2 farther than sigma' 'warning: .*% of M2 is farther than sigma from phi\(M1\): the deformed source does not reach that part of the target .*--second-path-target on' -- "${FIG[@]:0:2}" -o "$SCRATCH/tr0" --levels 8..8 --max-iterations 0 --quiet
check target-residual-target-on 0 'second path: .*% of M1 ended farther than sigma from M2 and .*% of M2 from phi\(M1\) on the first path; energies .*% of M2\).*: kept path' '' -- "${FIG[@]}" -o "$SCRATCH/spt" --second-path-target on
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/tr" "$SCRATCH/tr0" "$SCRATCH/spt" "$SCRATCH/sp" "$SCRATCH/m3" <<'PY'; then echo "ok   target-residual-report"; else fail "target-residual-report"; fi
import json, sys
reached, identity, target_on, source_only, default3 = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
for r in (reached, identity, default3):
    t = r["result"]["targetResidual"]
    assert set(t) == {"meanWorld", "maxWorld", "meanUnit", "maxUnit", "samples", "farShare", "capped", "maxVertex", "maxAtWorld"}, t
    assert len(t["maxAtWorld"]) == r["dimension"] and 0 <= t["maxVertex"] < t["samples"], t
    assert t["capped"] == 0 and r["result"]["residual"]["capped"] == 0, r["result"]
    assert t["samples"] == r["target"]["vertices"], (t, r["target"])
    assert abs(t["meanWorld"] - t["meanUnit"] / r["placement"]["scale"]) <= 1e-9 * t["meanWorld"] + 1e-15
    assert 0 <= t["meanUnit"] <= t["maxUnit"], t
h = 2.0 ** -6
assert reached["result"]["targetResidual"]["farShare"] == 0 and reached["result"]["targetResidual"]["meanUnit"] < h / 2
far = identity["result"]["targetResidual"]
assert far["farShare"] > 0.01 and far["maxUnit"] > 2 * 2.0 ** -8, far
assert default3["parameters"]["secondPathTarget"] == "off" and target_on["parameters"]["secondPathTarget"] == "on"
sp, sp0 = target_on["secondPath"], source_only["secondPath"]
assert sp["ran"] and "targetFarShare" in sp and all("targetFarShare" in p for p in sp["paths"]), sp
# M1 is left behind on this run, so the first path is the same with or without the option.
assert sp["paths"][0]["energy"] == sp0["paths"][0]["energy"] and sp["targetFarShare"] == sp0["targetFarShare"]
assert target_on["result"]["targetResidual"]["farShare"] == sp["paths"][sp["kept"]]["targetFarShare"]
PY
check trial-growth-range 3 '' 'grow must be finite and >= 1' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --trial-growth 0.5 --quiet
check trial-growth 0 'converged|not converged' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/tg" --levels 3..4 --trial-growth 1.5 --quiet
count=$((count + 1))
if "$PYTHON" -c 'import json, sys; p = json.load(open(sys.argv[1]))["parameters"]; q = json.load(open(sys.argv[2]))["parameters"]; sys.exit(0 if p["trialGrowth"] == 1.5 and q["trialGrowth"] == 2 else 1)' "$SCRATCH/tg/report.json" "$SCRATCH/m3/report.json"; then
    echo "ok   trial-growth-report"
else
    fail "trial-growth-report"
fi

# ---------------------------------------------------------------- landmarks (an addition to the paper)
if [ -f "$FIGURE_A" ] && [ -f "$FIGURE_B" ]; then
    # Three points of each figure's outline (the hands and the head, roughly), as tables.
    "$PYTHON" - "$FIGURE_A" "$FIGURE_B" "$SCRATCH" <<'PY'
import sys
def points(path):
    return [l.split()[:2] for l in open(path) if l.strip() and not l.startswith("#")]
a, b = points(sys.argv[1]), points(sys.argv[2])
def pick(p):  # lowest-left, rightmost, top vertex: defined on any outline
    xs = [(float(x), float(y)) for x, y in p]
    return [min(xs, key=lambda q: (q[1], q[0])), max(xs, key=lambda q: q[0]), max(xs, key=lambda q: q[1])]
for name, p in (("lm_a.csv", a), ("lm_b.csv", b)):
    open(sys.argv[3] + "/" + name, "w").write("x,y\n" + "".join("%r,%r\n" % q for q in pick(p)))
open(sys.argv[3] + "/lm_short.csv", "w").write("x,y\n0,0\n")
open(sys.argv[3] + "/lm_far.csv", "w").write("x,y\n1e3,0\n0,1\n2,2\n")
PY
    check landmarks-one-file 1 '' '--landmarks takes two files' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmarks "$SCRATCH/lm_a.csv" --quiet
    check landmarks-missing 2 '' 'lm_none.csv' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmarks "$SCRATCH/lm_a.csv" "$SCRATCH/lm_none.csv" --quiet
    check landmarks-counts 3 '' 'has 3 points but .*lm_short.csv has 1' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmarks "$SCRATCH/lm_a.csv" "$SCRATCH/lm_short.csv" --quiet
    check landmarks-outside 3 '' 'source landmark 1 lies outside the unit box' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmarks "$SCRATCH/lm_far.csv" "$SCRATCH/lm_a.csv" --quiet
    check landmarks-weight 1 '' '--landmark-weight' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmarks "$SCRATCH/lm_a.csv" "$SCRATCH/lm_b.csv" --landmark-weight x --quiet
    check match-2d-landmarks 0 'converged|not converged' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2l" --levels 4..6 --quiet --landmarks "$SCRATCH/lm_a.csv" "$SCRATCH/lm_b.csv"
    # --config of that report.json reruns it with the same landmarks and the same result.
    check match-2d-landmarks-config 0 'converged|not converged' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2lc" --config "$SCRATCH/m2l/report.json" --quiet
    count=$((count + 1))
    if "$PYTHON" - "$SCRATCH/m2" "$SCRATCH/m2l" "$SCRATCH/m2lc" <<'PY'; then echo "ok   landmarks-report"; else fail "landmarks-report"; fi
import json, sys
plain, lm, again = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
L = lm["landmarks"]
assert L["count"] == 3 and L["source"].endswith("lm_a.csv") and L["target"].endswith("lm_b.csv"), L
assert L["meanWorld"] < 0.5 * L["startMeanWorld"], L
assert lm["parameters"]["landmarks"] == [L["source"], L["target"]]
assert lm["result"]["terms"]["landmarks"] > 0
# Given landmarks replace the automatic ones; the extremities, still paired, only decide the
# automatic anchors, which act beside them (--landmark-anchors on, the default): the same
# anchors as without landmarks. By default the finest level's landmark term is that of the
# automatic anchors (the automatic landmarks act at levels 4..5 only).
A = lm["autoLandmarks"]
assert not A["used"] and "given landmarks" in A["reason"] and len(A["pairs"]) == 5, A
assert lm["innerDistance"]["used"], lm["innerDistance"]  # from the paired extremities
assert plain["autoLandmarks"]["used"], plain["autoLandmarks"]
assert A["anchors"] == plain["autoLandmarks"]["anchors"] > 0, (A, plain["autoLandmarks"])
assert lm["parameters"]["landmarkAnchors"] == "on"
assert (plain["result"]["terms"]["landmarks"] > 0) == (plain["autoLandmarks"]["anchors"] > 0)
assert "landmarks" not in plain and "landmarks" not in plain["parameters"]
assert lm["result"]["residual"]["meanUnit"] < lm["levels"][-1]["h"] / 2
assert again["landmarks"] == L and again["result"]["energy"] == lm["result"]["energy"], again["landmarks"]
PY
    # Automatic landmarks: the figures' five extremities (head, hands, feet), paired, act at
    # the first two levels only (by default whenever paired); the reverse run pairs the same
    # points the other way. The bundled pair moves its extremities by less than sigma of
    # level 4: with --auto-landmark-min-motion 1 the landmarks do not act (the result is that
    # of --auto-landmarks off).
    check auto-landmarks-bad 1 '' "--auto-landmarks expects 'on' or 'off'" -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --auto-landmarks yes --quiet
    check auto-landmark-levels-bad 3 '' 'autoLandmarkLevels must be >= 1' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --auto-landmarks on --auto-landmark-levels 0 --quiet
    check auto-landmark-min-motion-bad 3 '' 'autoLandmarkMinMotion must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --auto-landmarks on --auto-landmark-min-motion -1 --quiet
    check match-2d-auto-landmarks-small 0 'automatic landmarks: not used: every extremity moves by less than 1 sigma' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2g" --levels 4..6 --auto-landmark-min-motion 1
    check match-2d-auto-landmarks-off 0 'converged|not converged' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2o" --levels 4..6 --auto-landmarks off
    check match-2d-auto-landmarks 0 'automatic landmarks: 5 extremities paired .*, with [0-9]+ still anchors at every level' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2a" --levels 4..6
    check match-2d-auto-landmarks-no-anchors 0 'automatic landmarks: 5 extremities paired \(distortion [0-9.]*, largest motion [0-9.e-]* > 0 of the unit box\), acting at levels 4..5$' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2n" --levels 4..6 --auto-anchors off
    check auto-anchors-bad 1 '' "--auto-anchors expects 'on' or 'off'" -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --auto-anchors 1 --quiet
    check landmark-anchors-bad 1 '' "--landmark-anchors expects 'on' or 'off'" -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --landmark-anchors yes --quiet
    check anchor-count-bad 1 '' '--anchor-count must be >= 1' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --anchor-count 0 --quiet
    check anchor-weight-bad 3 '' 'anchorWeight must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --anchor-weight -1 --quiet
    check anchor-radius-bad 3 '' 'the anchor tolerance and radius must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --anchor-radius -0.1 --quiet
    check rigid-limb-weight-bad 3 '' 'rigidLimbWeight must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-limb-weight -1 --quiet
    check rigid-limb-min-motion-bad 3 '' 'rigidLimbMinMotion must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-limb-min-motion -1 --quiet
    check rigid-limb-count-bad 1 '' '--rigid-limb-count must be >= 2' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-limb-count 1 --quiet
    check rigid-limb-reach-bad 1 '' '--rigid-limb-reach must be in \(0, 0.8\]' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-limb-reach 0.9 --quiet
    check rigid-segment-bad 1 '' '--rigid-segment needs 0 <= FROM < TO <= 1, got 0.8,0.5' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-segment 0.8,0.5 --quiet
    check rigid-segment-form-bad 1 '' '--rigid-segment takes FROM,TO or off, got 0.5' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-segment 0.5 --quiet
    check rigid-segment-min-angle-bad 1 '' '--rigid-segment-min-angle must be >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-segment-min-angle -1 --quiet
    check rigid-segment-tip-motion-bad 1 '' '--rigid-segment-tip-motion must be >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --rigid-segment-tip-motion -1 --quiet
    check match-2d-auto-landmarks-reverse 0 'automatic landmarks: 5 extremities paired' '' -- "$FIGURE_B" "$FIGURE_A" -o "$SCRATCH/m2ar" --levels 4..6
    check match-2d-auto-landmarks-config 0 'automatic landmarks: 5' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2ac" --config "$SCRATCH/m2a/report.json"
    check match-2d-anchor-count 0 'with [1-7] still anchors at every level' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2c7" --levels 4..4 --anchor-count 7
    check inner-distance-weight-bad 3 '' 'the inner-distance weight and tolerance must be finite and >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --inner-distance-weight -1 --quiet
    check inner-distance-levels-bad 1 '' '--inner-distance-levels must be >= 0' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --inner-distance-levels -1 --quiet
    check inner-distance-level-bad 1 '' '--inner-distance-level must be in \[0, 9\]' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --inner-distance-level 12 --quiet
    check match-2d-inner-distance-progress 0 '' 'inner distance: F from each paired extremity on the lattice of level 8 \([0-9.]+ s\), over [0-9]+ vertices of M1, weight 1000, tolerance 0.01' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2fp" --levels 4..4
    check inner-distance-ratio-bad 1 '' '--inner-distance-ratio must be finite and >= 1, got 0.5' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/o" --inner-distance-ratio 0.5 --quiet
    check match-2d-inner-distance-ratio 0 '' 'inner distance: F from each paired extremity on the lattice of level 8 \([0-9.]+ s\), over [0-9]+ vertices of M1 \([0-9]+% of it: those whose second-nearest extremity is at least 1.5x as far as their nearest\), weight 1000' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2fr" --levels 4..4 --inner-distance-ratio 1.5
    check match-2d-inner-distance 0 'inner distance: \|F2_k\(phi\(x\)\) - F1_k\(x\)\| over M1 [0-9.e-]+ \([0-9.e-]+ at phi = Id\)' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2f" --levels 4..6 --inner-distance-weight 1000 --inner-distance-levels 2
    check match-2d-inner-distance-no-landmarks 0 'inner distance: not used: the automatic landmarks do not act' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2fo" --levels 4..4 --inner-distance-weight 1000 --auto-landmarks off
    check match-2d-inner-distance-config 0 'inner distance: ' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2fc" --config "$SCRATCH/m2f/report.json"
    # A report of a version before the term reproduces its run without it.
    "$PYTHON" -c 'import json, sys; r = json.load(open(sys.argv[1])); r["parameters"].pop("innerDistanceWeight"); json.dump(r, open(sys.argv[2], "w"))' "$SCRATCH/m2a/report.json" "$SCRATCH/old_inner.json"
    check match-2d-inner-distance-old-config 0 '' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2fold" --config "$SCRATCH/old_inner.json" --quiet
    # ... and one from before innerDistanceRatio kept every vertex in the term.
    "$PYTHON" -c 'import json, sys; r = json.load(open(sys.argv[1])); r["parameters"].pop("innerDistanceRatio"); json.dump(r, open(sys.argv[2], "w"))' "$SCRATCH/m2fr/report.json" "$SCRATCH/old_ratio.json"
    check match-2d-inner-distance-old-ratio 0 '' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2frold" --config "$SCRATCH/old_ratio.json" --quiet
    count=$((count + 1))
    if "$PYTHON" - "$SCRATCH/m2f" "$SCRATCH/m2fo" "$SCRATCH/m2fc" "$SCRATCH/m2a" "$SCRATCH/m2fold" "$SCRATCH/m3" "$SCRATCH/m2n" "$SCRATCH/m2fr" "$SCRATCH/m2fp" "$SCRATCH/m2frold" <<'PY'; then echo "ok   inner-distance-report"; else fail "inner-distance-report"; fi
import json, sys
f, off, again, auto, old, m3, bare, one, every, oldratio = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
F = f["innerDistance"]
assert F["used"] and F["reason"] is None and F["weight"] == 1000 and F["tolerance"] == 0.01, F
# --inner-distance-ratio 1.5 leaves out the points about as near to two extremities; the
# default, 1, keeps every vertex (all of M1's measure), and so does a run from an old report
# (no innerDistanceRatio), here one of ratio 1.5.
A, E = one["innerDistance"], every["innerDistance"]
assert one["parameters"]["innerDistanceRatio"] == 1.5 and A["ratio"] == 1.5, A
assert every["parameters"]["innerDistanceRatio"] == 1 and E["ratio"] == 1, E
assert 0.3 < A["share"] < 0.95 and abs(E["share"] - 1) < 1e-9, (A, E)
assert 100 < A["points"] < E["points"], (A, E)
assert oldratio["parameters"]["innerDistanceRatio"] == 1 and oldratio["innerDistance"]["points"] == E["points"]
assert F["level"] == 8 and F["points"] > 100, F  # 2D: F on the lattice of level 8
# The term keeps F: less of M1 beyond the tolerance, and a lower mean, than at phi = Id.
assert F["mean"] < F["startMean"] and F["beyond"] < F["startBeyond"], F
# It acts at the first two levels (4, 5), not at 6.
terms = [l["terms"]["innerDistance"] for l in f["levels"]]
assert terms[0] > 0 and terms[1] > 0 and terms[2] == 0, terms
P = f["parameters"]
assert P["innerDistanceWeight"] == 1000 and P["innerDistanceLevels"] == 2 and P["innerDistanceLevel"] == 0, P
O = off["innerDistance"]
assert not O["used"] and O["reason"] == "the automatic landmarks do not act", O
assert again["innerDistance"] == dict(F, seconds=again["innerDistance"]["seconds"])
assert again["result"]["energy"] == f["result"]["energy"]
# The 2D default: c_F = 1000 at every level, when the anchors act (the bundled figure has them).
assert auto["parameters"]["innerDistanceWeight"] == 1000 and auto["parameters"]["innerDistanceLevels"] == 0
assert auto["innerDistance"]["used"] and auto["autoLandmarks"]["anchors"] > 0, auto["innerDistance"]
assert all(l["terms"]["innerDistance"] > 0 for l in auto["levels"]), [l["terms"] for l in auto["levels"]]
# Off (weight 0): not reported, no term; an old report's run, and the 3D default, are off.
assert old["parameters"]["innerDistanceWeight"] == 0 and "innerDistance" not in old, old["parameters"]
assert all(l["terms"]["innerDistance"] == 0 for l in old["levels"])
assert m3["parameters"]["innerDistanceWeight"] == 0 and "innerDistance" not in m3
# Without anchors (--auto-anchors off) the term does not act, and says why.
B = bare["innerDistance"]
assert not B["used"] and B["reason"].startswith("the automatic anchors do not act"), B
assert all(l["terms"]["innerDistance"] == 0 for l in bare["levels"])
PY
    count=$((count + 1))
    if "$PYTHON" - "$SCRATCH/m2o" "$SCRATCH/m2a" "$SCRATCH/m2ar" "$SCRATCH/m2ac" "$SCRATCH/m2g" "$SCRATCH/m2n" <<'PY'; then echo "ok   auto-landmarks-report"; else fail "auto-landmarks-report"; fi
import json, sys
plain, auto, rev, again, small, bare = (json.load(open(d + "/report.json")) for d in sys.argv[1:])
G = small["autoLandmarks"]
assert G["paired"] and not G["used"] and G["maxMotion"] < G["minMotion"] == 0.125, G
assert small["parameters"]["autoLandmarks"] == "on" and G["pairs"] == [], G
assert small["result"]["energy"] == plain["result"]["energy"], (small["result"], plain["result"])
A = auto["autoLandmarks"]
assert A["used"] and A["reason"] is None and A["sourceExtremities"] == A["targetExtremities"] == 5, A
assert A["maxMotion"] == G["maxMotion"] and A["minMotion"] == 0, A
assert A["lastLevel"] == 5 and auto["parameters"]["autoLandmarks"] == "on", A
assert auto["parameters"]["autoLandmarkLevels"] == 2
assert A["meanWorld"] < A["startMeanWorld"], A
# Without anchors the landmark term acts at levels 4 and 5, not at 6; with them (the
# default), the anchors hold M1's still parts at every level.
B = bare["autoLandmarks"]
assert B["anchors"] == 0 and bare["parameters"]["autoAnchors"] == "off", B
terms = [l["terms"]["landmarks"] for l in bare["levels"]]
assert terms[0] > 0 and terms[1] > 0 and terms[2] == 0, terms
assert auto["parameters"]["autoAnchors"] == "on" and auto["parameters"]["anchorCount"] == 100  # 2D
assert 0 < A["anchors"] <= 100 and 0 < A["anchorCoincidentShare"] < 1, A
# The anchors' tolerance follows the shapes' correlated noise (an addition), in 3D only by
# default: these outlines keep the fixed tolerance.
assert auto["parameters"]["anchorNoiseTolerance"] == 0, auto["parameters"]
assert A["anchorTolerance"] == auto["parameters"]["anchorTolerance"] == 0.002, A
terms = [l["terms"]["landmarks"] for l in auto["levels"]]
assert all(t > 0 for t in terms), terms
assert small["autoLandmarks"]["anchors"] == 0  # no landmarks, no anchors
assert small["parameters"]["autoLandmarkMinMotion"] == 1 and auto["parameters"]["autoLandmarkMinMotion"] == 0
# Off: not reported; a config of the run reproduces it.
assert "autoLandmarks" not in plain and plain["parameters"]["autoLandmarks"] == "off"
assert again["autoLandmarks"] == dict(A, seconds=again["autoLandmarks"]["seconds"])
assert again["result"]["energy"] == auto["result"]["energy"]
# The reverse pairs the same points, swapped.
fwd = sorted((tuple(p["source"]), tuple(p["target"])) for p in A["pairs"])
back = sorted((tuple(p["target"]), tuple(p["source"])) for p in rev["autoLandmarks"]["pairs"])
assert fwd == back, (fwd, back)
PY
fi

# ---------------------------------------------------------------- one run per OUTDIR; SIGKILL leaves no result
"$VDB_MATCH" "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/busy" --levels 4..6 --quiet >/dev/null 2>&1 &
busy=$!
for _ in $(seq 1 100); do [ -e "$SCRATCH/busy/.vdb_match.lock" ] && break; sleep 0.1; done
check concurrent-outdir 2 '' 'another vdb_match is writing' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/busy" --levels 3..3 --quiet
kill -KILL "$busy" 2>/dev/null
wait "$busy" 2>/dev/null
count=$((count + 1))
# Killed before writing: nothing that looks like a result (temporary files are hidden).
if ls "$SCRATCH/busy" | grep -q .; then
    fail "sigkill: files left after SIGKILL: $(ls "$SCRATCH/busy" | tr '\n' ' ')"
else
    echo "ok   sigkill-leaves-no-result"
fi
check outdir-free-after-kill 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/busy" --levels 3..3 --quiet

# ---------------------------------------------------------------- interrupted (5)
count=$((count + 1))
"$VDB_MATCH" "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/int" --levels 4..8 --progress-every 1 >"$SCRATCH/out" 2>"$SCRATCH/err" &
pid=$!
for _ in $(seq 1 600); do
    grep -q 'level 5 it' "$SCRATCH/err" && break
    sleep 0.1
done
kill -INT "$pid" 2>/dev/null
wait "$pid"
code=$?
if [ "$code" -eq 5 ] && "$PYTHON" -c '
import json, sys, pyopenvdb as vdb
d = sys.argv[1]
assert vdb.read(d + "/deformation.vdb", "displacement").metadata["is_interrupted"] is True
r = json.load(open(d + "/report.json"))
assert r["status"] == "interrupted" and "inverse.vdb" not in r["outputs"]
' "$SCRATCH/int" && [ ! -e "$SCRATCH/int/inverse.vdb" ]; then
    echo "ok   interrupted"
else
    fail "interrupted: exit code $code, expected 5 and outputs marked interrupted"
    tail -5 "$SCRATCH/err"
fi

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
