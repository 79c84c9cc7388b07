#!/usr/bin/env bash
# CLI tests of `vdb_match energy` on every input `match` reads: 2D polylines and one-layer .vdb
# slices are 2D (two simplices per cell, 2D defaults), meshes are 3D; the energy equals the
# initial energy of `match` at the same level (same reading, placement and distance fields).
# Usage: test_cli_energy_inputs.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_energy_inputs.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_energy_inputs.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SLICE_A="$ASSETS/figure_a_slice.vdb"
SLICE_B="$ASSETS/figure_b_slice.vdb"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-energy.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT
PYTHON=${VDBMATCH_PYTHON:-python3}

source "$(dirname "$0")/common.sh"

# same_energy NAME LEVEL SOURCE TARGET DIM [OPTIONS...]: energy --json total == match --levels L..L
# initial energy, both with OPTIONS (without automatic landmarks, whose term `energy` does not
# have, and with the paper's membrane density and distance Hessian unless OPTIONS change them
# (match's default smooths the Hessian of noisy shapes, energy's does not):
# match's default saturates the membrane at its first levels, `energy`'s does not). The directional energy of the identity holds c_vol sigma^theta W_vol(1)|Omega|, so its
# runs also check that both commands default to the same c_vol.
same_energy() {
    local name=$1 level=$2 source=$3 target=$4 dim=$5
    shift 5
    count=$((count + 1))
    "$VDB_MATCH" energy "$source" "$target" --level "$level" --json --quiet "$@" >"$SCRATCH/$name.json" 2>"$SCRATCH/err" &&
        "$VDB_MATCH" "$source" "$target" -o "$SCRATCH/$name" --levels "$level..$level" --max-iterations 0 \
            --auto-landmarks off --membrane-saturation 0 --hessian-smoothing 0 --noise-smoothing 0 --quiet --no-inverse --no-jacobian \
            "$@" >/dev/null 2>>"$SCRATCH/err"
    local code=$?
    if [ "$code" -eq 0 ] && "$PYTHON" - "$SCRATCH/$name.json" "$SCRATCH/$name/report.json" "$dim" <<'PY'; then
import json, sys
e = json.load(open(sys.argv[1]))
m = json.load(open(sys.argv[2]))
dim = int(sys.argv[3])
assert e["dimension"] == dim and m["dimension"] == dim, (e["dimension"], m["dimension"])
cells = 2 ** (dim * e["level"])
assert e["simplices"] == cells * (2 if dim == 2 else 6), e["simplices"]
initial = m["levels"][0]["initialEnergy"]
assert abs(e["total"] - initial) <= 1e-9 * abs(initial), (e["total"], initial)
assert e["placement"] == m["placement"], (e["placement"], m["placement"])
for key in ("cMatch", "cMem", "cBend", "cVol", "q", "theta", "membraneSaturation", "hessianSmoothing",
            "noiseSmoothing", "latticeNoiseSmoothing", "noiseBending"):
    assert e["parameters"][key] == m["parameters"][key], (key, e["parameters"], m["parameters"])
PY
        echo "ok   $name"
    else
        fail "$name: energy differs from match's initial energy (exit code $code)"
        sed 's/^/  /' "$SCRATCH/err" | tail -5
    fi
}

same_energy polyline-2d 6 "$FIGURE_A" "$FIGURE_B" 2
same_energy slice-2d 6 "$SLICE_A" "$SLICE_B" 2
same_energy level-set-3d 4 "$SPHERE" "$ELLIPSOID" 3
same_energy directional-2d 6 "$FIGURE_A" "$FIGURE_B" 2 --energy directional
same_energy directional-3d 4 "$SPHERE" "$ELLIPSOID" 3 --energy directional --c-vol 2
same_energy saturated-2d 6 "$FIGURE_A" "$FIGURE_B" 2 --membrane-saturation 0.01
same_energy saturated-3d 4 "$SPHERE" "$ELLIPSOID" 3 --membrane-saturation 0.01
same_energy smoothed-3d 4 "$SPHERE" "$ELLIPSOID" 3 --hessian-smoothing 2
# A target with a scanner's noise (0.3% of its size along the normal), smoothed from its noise.
"$PYTHON" - "$FIGURE_B" "$SCRATCH/figure_b_scan.polyline" <<'PY'
import math, random, sys
curves, cur = [], []
for line in open(sys.argv[1]):
    line = line.split("#")[0].split()
    if not line:
        if cur: curves.append(cur); cur = []
        continue
    cur.append((float(line[0]), float(line[1])))
if cur: curves.append(cur)
xs = [p[0] for c in curves for p in c]; ys = [p[1] for c in curves for p in c]
sigma = 0.003 * math.hypot(max(xs) - min(xs), max(ys) - min(ys))
rng = random.Random(5)
with open(sys.argv[2], "w") as out:
    for c in curves:
        for i, (x, y) in enumerate(c):
            (ax, ay), (bx, by) = c[i - 1], c[(i + 1) % len(c)]
            tx, ty = bx - ax, by - ay
            t = math.hypot(tx, ty) or 1.0
            e = rng.gauss(0.0, sigma)
            out.write("%.9g %.9g\n" % (x + e * ty / t, y - e * tx / t))
        out.write("\n")
PY
same_energy noise-smoothed-2d 8 "$FIGURE_A" "$SCRATCH/figure_b_scan.polyline" 2 --noise-smoothing 4
count=$((count + 1))
if "$VDB_MATCH" energy "$FIGURE_A" "$SCRATCH/figure_b_scan.polyline" --level 8 --json --quiet >"$SCRATCH/n0.json" &&
    "$PYTHON" - "$SCRATCH/n0.json" "$SCRATCH/noise-smoothed-2d.json" "$SCRATCH/noise-smoothed-2d/report.json" <<'PY'; then echo "ok   noise-smoothing-acts"; else fail "noise-smoothing-acts"; fi
import json, sys
plain, smoothed, report = (json.load(open(f)) for f in sys.argv[1:])
assert plain["parameters"]["noiseSmoothing"] == 0 and smoothed["parameters"]["noiseSmoothing"] == 4
# Only the bending term reads the Hessian (eq:defSi); the target's is smoothed, the source's not.
assert plain["terms"]["bend"] != smoothed["terms"]["bend"], (plain["terms"], smoothed["terms"])
for k in ("match", "mem", "vol"):
    assert plain["terms"][k] == smoothed["terms"][k], (k, plain["terms"], smoothed["terms"])
noise = report["noise"]
assert "noise" not in plain and smoothed["noise"] == noise, (smoothed.get("noise"), noise)
assert noise["target"] > 30 * noise["source"] > 0, noise
assert noise["smoothingLength"] == [4 * noise["source"], 4 * noise["target"]], noise
PY
# 3D reads each shape's noise on a lattice too (an addition, match's 3D default): both commands
# read the same, and --lattice-noise-smoothing 0 turns it off.
same_energy lattice-noise-3d 4 "$SPHERE" "$ELLIPSOID" 3 --noise-smoothing 16
count=$((count + 1))
if "$VDB_MATCH" energy "$SPHERE" "$ELLIPSOID" --level 4 --json --quiet --noise-smoothing 16 --lattice-noise-smoothing 0 >"$SCRATCH/l0.json" &&
    "$PYTHON" - "$SCRATCH/lattice-noise-3d.json" "$SCRATCH/lattice-noise-3d/report.json" "$SCRATCH/l0.json" <<'PY'; then echo "ok   lattice-noise-3d-read"; else fail "lattice-noise-3d-read"; fi
import json, sys
energy, report, off = (json.load(open(f)) for f in sys.argv[1:])
assert energy["parameters"]["latticeNoiseSmoothing"] == 3.5 == report["parameters"]["latticeNoiseSmoothing"]
assert energy["noise"] == report["noise"], (energy["noise"], report["noise"])
noise = energy["noise"]
assert all(0 < v < 1e-3 for v in noise["lattice"]), noise
for i, shape in enumerate(("source", "target")):
    assert noise["smoothingLength"][i] == max(16 * noise[shape], 3.5 * noise["lattice"][i]), noise
assert off["parameters"]["latticeNoiseSmoothing"] == 0 and off["noise"]["lattice"] == [0, 0], off["noise"]
assert off["noise"]["smoothingLength"] == [16 * off["noise"]["source"], 16 * off["noise"]["target"]], off["noise"]
PY
# The bending weight follows the passes of the noise smoothing (an addition): the term scales by
# the level's factor, 1 / (1 + n / P), and nothing else changes.
count=$((count + 1))
if "$VDB_MATCH" energy "$FIGURE_A" "$SCRATCH/figure_b_scan.polyline" --level 8 --json --quiet --noise-smoothing 4 --noise-bending 0 >"$SCRATCH/nb0.json" &&
    "$PYTHON" - "$SCRATCH/nb0.json" "$SCRATCH/noise-smoothed-2d.json" <<'PY'; then echo "ok   noise-bending-scales-bend"; else fail "noise-bending-scales-bend"; fi
import json, sys
off, on = (json.load(open(f)) for f in sys.argv[1:])
assert off["parameters"]["noiseBending"] == 0 and on["parameters"]["noiseBending"] == 4
assert off["bendingFactor"] == 1 and 0 < on["bendingFactor"] < 1, (off["bendingFactor"], on["bendingFactor"])
# n passes: the factor is 4 / (4 + n) for a whole n >= 1
n = 4 / on["bendingFactor"] - 4
assert n >= 1 and abs(n - round(n)) < 1e-9, n
bend_on, bend_off = on["terms"]["bend"], off["terms"]["bend"]
assert len(bend_on) == len(bend_off) == 2 and min(bend_off) > 0, (bend_on, bend_off)
for a, b in zip(bend_on, bend_off):  # the direct and the inverse half
    assert abs(a - on["bendingFactor"] * b) <= 1e-12 * b, (bend_on, bend_off)
for k in ("match", "mem", "vol"):
    assert on["terms"][k] == off["terms"][k], (k, on["terms"], off["terms"])
PY
# The saturation lowers the membrane term only (an addition: s log(1 + W/s) <= W).
count=$((count + 1))
if "$VDB_MATCH" energy "$FIGURE_A" "$FIGURE_B" --level 6 --json --quiet >"$SCRATCH/e0.json" &&
    "$VDB_MATCH" energy "$FIGURE_A" "$FIGURE_B" --level 6 --json --quiet --membrane-saturation 0.01 >"$SCRATCH/e1.json" &&
    "$PYTHON" - "$SCRATCH/e0.json" "$SCRATCH/e1.json" <<'PY'; then echo "ok   saturation-lowers-membrane"; else fail "saturation-lowers-membrane"; fi
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:])
assert a["parameters"]["membraneSaturation"] == 0 and b["parameters"]["membraneSaturation"] == 0.01
for half in (0, 1):
    assert 0 < b["terms"]["mem"][half] < 0.99 * a["terms"]["mem"][half], (a["terms"], b["terms"])
    for k in ("match", "bend", "vol"):
        assert b["terms"][k][half] == a["terms"][k][half], (k, a["terms"], b["terms"])
PY

# A mesh (match's deformed.obj of the sphere) against a level set.
"$VDB_MATCH" "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m" --levels 3..3 --quiet --no-inverse --no-jacobian >/dev/null 2>&1
same_energy mesh-3d 4 "$SCRATCH/m/deformed.obj" "$ELLIPSOID" 3

check polyline-human 0 '2D, level 6' '' -- energy "$FIGURE_A" "$FIGURE_B" --level 6 --quiet
check polyline-defaults-2d 0 '"cMatch": 0.512' '' -- energy "$FIGURE_A" "$FIGURE_B" --level 5 --json --quiet
check polyline-override 0 '"cMatch": 2' '' -- energy "$FIGURE_A" "$FIGURE_B" --level 5 --json --quiet --c-match 2
check level-9-2d 0 'total' '' -- energy "$FIGURE_A" "$FIGURE_B" --level 9 --quiet
check level-9-3d 3 '' 'level must be in \[1, 8\] in 3D' -- energy "$SPHERE" "$ELLIPSOID" --level 9 --quiet
check level-12 3 '' 'level must be in \[1, 8\] in 3D, \[1, 11\] in 2D' -- energy "$FIGURE_A" "$FIGURE_B" --level 12 --quiet
check dimension-mismatch 3 '' '2D shape but' -- energy "$FIGURE_A" "$SPHERE" --quiet
check grid-polyline 1 '' '--grid applies to .vdb inputs' -- energy "$FIGURE_A" "$FIGURE_B" --grid surface
check identical-2d 0 'match +0\.0+e\+00 +0\.0+e\+00' '' -- energy "$FIGURE_A" "$FIGURE_A" --level 5 --quiet
# A small piece beside the target: warned as by match, and recorded in the JSON's inputs.
{ grep -v '^#' "$FIGURE_B"; printf '\n1.5 1.5\n1.52 1.5\n1.52 1.52\n1.5 1.52\n'; } >"$SCRATCH/fragment.polyline"
check small-piece-warned 0 '"smallPieces"' 'warning: the target has 2 pieces, 1 of them small \(4 vertices, 0\.9[0-9]% of its length\)' -- energy "$FIGURE_A" "$SCRATCH/fragment.polyline" --level 5 --json --quiet
if "$PYTHON" - "$SCRATCH/out" <<'PY'; then echo "ok   small-piece-json"; else fail "small-piece-json"; fi
import json, sys
j = json.load(open(sys.argv[1]))
assert j["source"]["pieces"] == 1 and j["source"]["smallPieces"]["count"] == 0, j["source"]
assert j["target"]["pieces"] == 2 and j["target"]["smallPieces"]["count"] == 1, j["target"]
assert j["target"]["smallPieces"]["vertices"] == 4, j["target"]
PY

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
