#!/usr/bin/env bash
# Peer benchmark (issue 8, item 4): vdb_match against an elastix B-spline registration of the
# same pair at the same resolution, in one run, side by side.
#
# Usage: bench/compare_elastix.sh [--vdb-match PATH] --pair DIR [--level L] [--out DIR]
#                                 [--threads N] [--vdbmatch-args "..."] [--tsv FILE]
#
# DIR holds source.obj, target.obj (closed 3D triangle meshes, world units), truth.xyz (one line
# "x y z" per vertex of source.obj: the ground-truth image g(v), world units) and optionally
# pair.json (bench/accuracy/make_pairs.py). Steps:
#   1. vdb_match SOURCE TARGET --levels 4..L --threads N (+ --vdbmatch-args); its report.json gives
#      the placement unit = scale * (world - worldOrigin) of both shapes in (0,1)^3;
#   2. both meshes, mapped to the unit box by that placement, become signed-distance volumes on the
#      nodes of level L: (2^L+1)^3 voxels of size h = 2^-L covering [0,1]^3, the same box and
#      spacing as vdb_match's finest level; distances exact near the surface (OpenVDB
#      meshToVolume, pyopenvdb), clamped at +-SDF_BAND beyond (only near the corners of the box);
#      written as MetaImage (.mhd + .raw, float; physical coordinates and distances in unit-box
#      lengths, so the elastix parameters below mean the same for every pair whatever its units);
#   3. elastix, fixed = source SDF, moving = target SDF (so the transform T maps source points to
#      target points), B-spline transform, multi-resolution, AdvancedMeanSquares, with the
#      parameter file written below (ELASTIX_* variables, which the environment may override),
#      with a bending-energy penalty (without it the stochastic optimizer lets the points drift
#      along the level sets of the SDFs at the fine resolutions and the transform folds), -threads N;
#      transformix -def on the source vertices gives phi_elastix(v) = T(v);
#      transformix -jac all (not timed) gives det DT on the voxels (folds: det <= 0);
#   4. for both methods: wall time and peak resident memory (GNU time), the residual |d2(phi(v))|
#      over the source vertices -- both measured the same way, by trilinear sampling of the target
#      SDF volume at phi(v) (vdb_match: the vertices of its deformed.obj), in unit-box units;
#      vdb_match's own exact residual (report.json result.residual.meanUnit) is printed too --
#      and the mean and 95th percentile of |phi(v) - g(v)| in unit-box units.
# The elastix time is elastix + transformix -def (the registration and the mapping of the
# vertices); building the SDF volumes (needed by elastix only) is reported separately and not
# counted. The ratio printed is vdb_match wall / elastix wall (< 1: vdb_match is faster).
#
# Installs elastix and GNU time with apt-get if missing (sudo when not root).
# Temporary files are removed unless --out is given. --tsv FILE appends the elastix row in the
# format of bench/compare_peers.sh's peers.tsv (pair, dim, peer, err_mean, err_p95, motion_mean,
# wall_s, peak_mb; unit-box lengths), for bench/accuracy/correspondence_table.py --peers.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
  sed -n '5,6p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 1
}

VDB_MATCH=build/tools/vdb_match/vdb_match
PAIR=""
LEVEL=7
OUT=""
THREADS=2
VDBMATCH_ARGS=""
TSV=""
while [ $# -gt 0 ]; do
  case "$1" in
    --vdb-match) VDB_MATCH=${2:?}; shift 2 ;;
    --vdb-match=*) VDB_MATCH=${1#*=}; shift ;;
    --pair) PAIR=${2:?}; shift 2 ;;
    --pair=*) PAIR=${1#*=}; shift ;;
    --level) LEVEL=${2:?}; shift 2 ;;
    --level=*) LEVEL=${1#*=}; shift ;;
    --out) OUT=${2:?}; shift 2 ;;
    --out=*) OUT=${1#*=}; shift ;;
    --threads) THREADS=${2:?}; shift 2 ;;
    --threads=*) THREADS=${1#*=}; shift ;;
    --vdbmatch-args) VDBMATCH_ARGS=${2?}; shift 2 ;;
    --vdbmatch-args=*) VDBMATCH_ARGS=${1#*=}; shift ;;
    --tsv) TSV=${2:?}; shift 2 ;;
    --tsv=*) TSV=${1#*=}; shift ;;
    -h|--help) usage ;;
    *) echo "compare_elastix.sh: unknown argument '$1'" >&2; usage ;;
  esac
done
[ -n "$PAIR" ] || { echo "compare_elastix.sh: --pair DIR is required" >&2; usage; }
for f in source.obj target.obj truth.xyz; do
  [ -f "$PAIR/$f" ] || { echo "compare_elastix.sh: $PAIR/$f not found (3D pairs only)" >&2; exit 1; }
done
if ! [[ "$LEVEL" =~ ^[0-9]+$ ]] || [ "$LEVEL" -lt 4 ] || [ "$LEVEL" -gt 9 ]; then
  echo "compare_elastix.sh: --level must be an integer in 4..9" >&2
  exit 1
fi
[ -x "$VDB_MATCH" ] || { echo "compare_elastix.sh: $VDB_MATCH is not executable (build first: bash tools/build.sh)" >&2; exit 1; }

# ---- elastix parameters (B-spline registration of the two SDF volumes) ------------------------
# bench/accuracy/elastix.sh holds them (ELASTIX_* variables, which the environment may override),
# the same as compare_peers.sh --elastix uses.
source bench/accuracy/elastix.sh
elastix_check || exit 1
SDF_BAND=${SDF_BAND:-0.3}                                  # SDF exact up to this distance (unit box), clamped beyond

PYTHON=python3
[ -x /usr/bin/python3 ] && PYTHON=/usr/bin/python3          # the system python has numpy and pyopenvdb

# ---- dependencies ----------------------------------------------------------------------------
need=()
command -v elastix >/dev/null && command -v transformix >/dev/null || need+=(elastix)
[ -x /usr/bin/time ] || need+=(time)
if [ ${#need[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  echo "compare_elastix.sh: installing ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get install -y "${need[@]}" >&2 ||
    { $SUDO apt-get update >&2 && $SUDO apt-get install -y "${need[@]}" >&2; }
fi
"$PYTHON" -c 'import numpy, pyopenvdb' 2>/dev/null ||
  { echo "compare_elastix.sh: $PYTHON needs numpy and pyopenvdb (apt-get install -y python3-numpy python3-openvdb)" >&2; exit 1; }

if [ -n "$OUT" ]; then
  mkdir -p "$OUT"
  WORK=$(cd "$OUT" && pwd)
else
  WORK=$(mktemp -d "${TMPDIR:-/tmp}/compare-elastix.XXXXXX")
  trap 'rm -rf "$WORK"' EXIT
fi
mkdir -p "$WORK/vdb_match" "$WORK/elastix" "$WORK/transformix" "$WORK/jacobian"
N=$(( (1 << LEVEL) + 1 ))

# ---- machine and parameters --------------------------------------------------------------------
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
PAIR_INFO=""
if [ -f "$PAIR/pair.json" ]; then
  PAIR_INFO=$("$PYTHON" -c 'import json, sys
d = json.load(open(sys.argv[1]))
print(" (" + ", ".join(f"{k}: {v}" for k, v in d.items() if not isinstance(v, (dict, list))) + ")")' "$PAIR/pair.json" 2>/dev/null) || PAIR_INFO=""
fi
echo "pair: $PAIR$PAIR_INFO"
echo "resolution: level $LEVEL, h = 2^-$LEVEL, SDF volumes ${N}^3 on the vdb_match placement; threads $THREADS"
echo "vdb_match: $VDB_MATCH ($("$VDB_MATCH" --version 2>&1 | head -1)) --levels 4..$LEVEL --threads $THREADS --quiet $VDBMATCH_ARGS"
echo "elastix $(elastix --version 2>&1 | head -1 | sed "s/^elastix version: //"): $(elastix_summary); SDF band +-$SDF_BAND"

# ---- 1. vdb_match ------------------------------------------------------------------------------
# shellcheck disable=SC2086
/usr/bin/time -f '%e %M' -o "$WORK/vdb_match/time.txt" \
  "$VDB_MATCH" match "$PAIR/source.obj" "$PAIR/target.obj" -o "$WORK/vdb_match" \
  --levels "4..$LEVEL" --threads "$THREADS" --quiet $VDBMATCH_ARGS \
  >"$WORK/vdb_match/stdout.txt" 2>"$WORK/vdb_match/stderr.txt" ||
  { echo "compare_elastix.sh: vdb_match failed:" >&2; cat "$WORK/vdb_match/stderr.txt" >&2; exit 1; }

# ---- 2. signed-distance volumes ----------------------------------------------------------------
cat >"$WORK/sdf.py" <<'PY'
# Builds the SDF volumes of both meshes on the level-L node grid of vdb_match's unit box, and the
# transformix point file of the source vertices.
import json, sys, time
import numpy as np

sys.path.insert(0, "bench/accuracy")
from sdf_images import read_obj, sdf_mesh, write_mhd, write_transformix_points  # noqa: E402

pair, work, level, band = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
placement = json.load(open(f"{work}/vdb_match/report.json"))["placement"]
origin, scale = np.array(placement["worldOrigin"], float), float(placement["scale"])
n = 2 ** level + 1
h = 2.0 ** -level  # voxel size: the volumes live in the unit box, unit-box lengths

t0 = time.time()
for name in ("source", "target"):
    pts, tris = read_obj(f"{pair}/{name}.obj")
    pts = scale * (pts - origin)  # unit box
    a = sdf_mesh(pts, tris, n, h, band)  # a[i, j, k] = d((i, j, k) * h), unit-box lengths
    write_mhd(f"{work}/{name}_sdf.mhd", a, h)
    if name == "source":
        write_transformix_points(f"{work}/source_points.txt", pts)
print(f"{time.time() - t0:.1f}")
PY
SDF_SECONDS=$("$PYTHON" "$WORK/sdf.py" "$PAIR" "$WORK" "$LEVEL" "$SDF_BAND")

# ---- 3. elastix and transformix ----------------------------------------------------------------
elastix_parameters 3 "$WORK/elastix/parameters.txt"

/usr/bin/time -f '%e %M' -o "$WORK/elastix/time.txt" \
  elastix -f "$WORK/source_sdf.mhd" -m "$WORK/target_sdf.mhd" -p "$WORK/elastix/parameters.txt" \
  -out "$WORK/elastix" -threads "$THREADS" >"$WORK/elastix/stdout.txt" 2>&1 ||
  { echo "compare_elastix.sh: elastix failed (last lines of its log):" >&2; tail -20 "$WORK/elastix/stdout.txt" >&2; exit 1; }
/usr/bin/time -f '%e %M' -o "$WORK/transformix/time.txt" \
  transformix -def "$WORK/source_points.txt" -tp "$WORK/elastix/TransformParameters.0.txt" \
  -out "$WORK/transformix" -threads "$THREADS" >"$WORK/transformix/stdout.txt" 2>&1 ||
  { echo "compare_elastix.sh: transformix failed:" >&2; tail -20 "$WORK/transformix/stdout.txt" >&2; exit 1; }
# det DT on the voxels, for the folds (not timed)
transformix -jac all -tp "$WORK/elastix/TransformParameters.0.txt" -out "$WORK/jacobian" \
  -threads "$THREADS" >"$WORK/jacobian/stdout.txt" 2>&1 || true

# ---- 4. evaluation -----------------------------------------------------------------------------
cat >"$WORK/evaluate.py" <<'PY'
import json, sys
import numpy as np

sys.path.insert(0, "bench/accuracy")
from sdf_images import read_transformix_points, sample  # noqa: E402

pair, work, level, sdfSeconds = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
tsv = sys.argv[5] if len(sys.argv) > 5 else ""
report = json.load(open(f"{work}/vdb_match/report.json"))
origin = np.array(report["placement"]["worldOrigin"], float)
scale = float(report["placement"]["scale"])
n = 2 ** level + 1
h = 2.0 ** -level


def objPoints(path):
    return np.array([[float(x) for x in l.split()[1:4]] for l in open(path) if l.startswith("v ")])


def readTime(path):
    wall, kb = open(path).read().split()[-2:]
    return float(wall), int(kb) / 1024.0


# the target SDF volume, a[i, j, k] at unit point (i, j, k) * h, unit-box distances
d2 = np.fromfile(f"{work}/target_sdf.raw", np.float32).reshape(n, n, n).transpose(2, 1, 0)


def trilinear(a, unit):
    return sample(a, h, unit)


def toUnit(world):
    return scale * (world - origin)


source = toUnit(objPoints(f"{pair}/source.obj"))
truth = toUnit(np.loadtxt(f"{pair}/truth.xyz", ndmin=2)[:, :3])
if len(truth) != len(source):
    sys.exit(f"compare_elastix.sh: truth.xyz has {len(truth)} points, source.obj {len(source)} vertices")
phiV = toUnit(objPoints(f"{work}/vdb_match/deformed.obj"))
phiE = read_transformix_points(f"{work}/transformix/outputpoints.txt", 3)
assert len(phiV) == len(source) and len(phiE) == len(source)

rows = {}
for name, phi in (("vdb_match", phiV), ("elastix", phiE)):  # unit box
    res = np.abs(trilinear(d2, phi))
    err = np.linalg.norm(phi - truth, axis=1)
    rows[name] = dict(res=res, err=err)

wallV, memV = readTime(f"{work}/vdb_match/time.txt")
wallR, memR = readTime(f"{work}/elastix/time.txt")
wallT, memT = readTime(f"{work}/transformix/time.txt")
wallE, memE = wallR + wallT, max(memR, memT)

detE = "n/a"
try:
    hdr = dict(l.split(" = ", 1) for l in open(f"{work}/jacobian/spatialJacobian.mhd").read().splitlines())
    J = np.fromfile(f"{work}/jacobian/" + hdr["ElementDataFile"].strip(), np.float32)
    # transformix -jac writes det DT (one channel); a 9-channel file would be DT itself
    det = J if J.size == n ** 3 else np.linalg.det(J.reshape(-1, 3, 3).astype(np.float64))
    detE = f"{det.min():.3f} ({np.count_nonzero(det <= 0)} voxels <= 0)"
except Exception as e:  # noqa: BLE001
    detE = f"n/a ({e.__class__.__name__})"
r = report["result"]
idId = np.linalg.norm(source - truth, axis=1)

print()
print(f"{'':34}{'vdb_match':>16}{'elastix':>16}")
print(f"{'wall time [s]':34}{wallV:>16.1f}{wallE:>16.1f}   (elastix {wallR:.1f} + transformix {wallT:.1f})")
print(f"{'peak memory [MB]':34}{memV:>16.0f}{memE:>16.0f}")
for label, key, f in (("residual |d2(phi(v))| mean", "res", np.mean),
                      ("residual |d2(phi(v))| max", "res", np.max),
                      ("|phi(v) - g(v)| mean", "err", np.mean),
                      ("|phi(v) - g(v)| 95th percentile", "err", lambda x: np.percentile(x, 95)),
                      ("|phi(v) - g(v)| max", "err", np.max)):
    print(f"{label:34}{f(rows['vdb_match'][key]):>16.3e}{f(rows['elastix'][key]):>16.3e}")
print(f"{'min det Dphi':34}{r['minJacobian']:>16.3f}   {detE}")
print()
print(f"wall-time ratio vdb_match / elastix: {wallV / wallE:.2f}")
print(f"units: lengths in the unit box (0,1)^3, h = 2^-{level} = {h:.3e}; residuals of both sampled the same way,")
print(f"  trilinearly in the {n}^3 target SDF volume at the vertices of phi(M1) ({len(source)} vertices);")
print(f"  vdb_match's own exact residual (report.json): mean {r['residual']['meanUnit']:.3e} max {r['residual']['maxUnit']:.3e};")
print(f"  for reference, phi = Id: |v - g(v)| mean {idId.mean():.3e}, residual mean "
      f"{np.abs(trilinear(d2, source)).mean():.3e}")
print(f"vdb_match status: {report['status']}; elastix time excludes building the SDF volumes ({sdfSeconds:.1f} s)")
if tsv:
    import os
    name = os.path.basename(os.path.normpath(pair))
    try:
        name = json.load(open(f"{pair}/pair.json"))["name"]
    except (OSError, KeyError, ValueError):
        pass
    err = rows["elastix"]["err"]
    new = not os.path.exists(tsv)
    with open(tsv, "a") as f:
        if new:
            f.write("pair\tdim\tpeer\terr_mean\terr_p95\tmotion_mean\twall_s\tpeak_mb\n")
        f.write(f"{name}\t3\telastix\t{err.mean():.6g}\t{np.percentile(err, 95):.6g}\t"
                f"{idId.mean():.6g}\t{wallE:.1f}\t{memE:.0f}\n")
PY
"$PYTHON" "$WORK/evaluate.py" "$PAIR" "$WORK" "$LEVEL" "$SDF_SECONDS" "$TSV"
[ -z "$OUT" ] || echo "outputs kept in $WORK"
