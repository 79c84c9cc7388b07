#!/usr/bin/env bash
# Point, mesh and image peers on the accuracy pairs (issue: correspondence): Bayesian Coherent
# Point Drift (BCPD, github.com/ohirose/bcpd), the AMM non-rigid registration of Yao et al.
# (github.com/yaoyx689/AMM_NRR), and ANTs SyN (github.com/ANTsX/ANTs) and elastix on the shapes'
# signed distances, each run as its users would, against the same known maps g as
# bench/bench_accuracy.sh. Only elastix is packaged in Debian 12 (apt-get install -y elastix);
# build the others yourself from their public sources. Give each peer's binary path; a peer
# without a path is skipped with a message. Not in CI.
# How they were built for docs/results.md (2026-11-26, Debian 12; their licences are theirs:
# AMM_NRR's README restricts it to research use):
#   apt-get install -y libopenblas-dev libopenmesh-dev   # then reset the BLAS alternative if
#       # you want reference BLAS back: update-alternatives --config libblas.so.3-x86_64-linux-gnu
#   BCPD (ohirose/bcpd daec198): make in the repository root -> ./bcpd (gcc -O3 -fopenmp, OpenBLAS)
#   AMM_NRR (yaoyx689/AMM_NRR 3621366): cmake -DCMAKE_BUILD_TYPE=Release .. && cmake --build .
#       -> build/AMM_NRR (bundled nanoflann, system Eigen and OpenMesh)
#   ANTs (ANTsX/ANTs v2.3.5, 2026-11-27; the last release for ITK 5.2): against Debian's ITK
#       (apt-get install -y libinsighttoolkit5-dev), cmake -G Ninja -DCMAKE_BUILD_TYPE=Release
#       -DANTS_SUPERBUILD=OFF -DUSE_SYSTEM_ITK=ON -DITK_DIR=/usr/lib/cmake/ITK-5.2
#       -DBUILD_TESTING=OFF -DBUILD_SHARED_LIBS=OFF -DUSE_VTK=OFF
#       -DCMAKE_CXX_FLAGS=-I<ITKGenericLabelInterpolator>/include SRC (the headers of
#       InsightSoftwareConsortium/ITKGenericLabelInterpolator 89da930, an ITK module Debian lacks),
#       then cmake --build . --target antsRegistration antsApplyTransformsToPoints (22 min, 2 cores)
# Set OMP_NUM_THREADS (and OPENBLAS_NUM_THREADS for BCPD) to compare at equal cores. AMM_NRR exits
# 0 even when it cannot write its result; the score step fails on the missing file instead.
#
# Usage: bench/compare_peers.sh [--pairs a,b,...] [--bcpd PATH] [--amm PATH] [--syn PATH]
#                               [--elastix PATH] [--out DIR] [--scan]
#   --pairs  names, or a set: all (default; make_pairs.py --list) or speed
#   --bcpd   the bcpd binary (built with its makefile; needs OpenBLAS/LAPACK)
#   --amm    the AMM_NRR binary (CMake; needs OpenMesh: Debian libopenmesh-dev); 3D only
#   --syn    ANTs' antsRegistration binary; antsApplyTransformsToPoints must be next to it
#   --elastix the elastix binary (Debian: /usr/bin/elastix); transformix must be next to it
#   --out    keep pairs and outputs in DIR (pairs are reused as bench_accuracy.sh does)
#   --scan   map onto the target with a scanner's noise (make_pairs.py target_scan.*, as
#            bench_accuracy.sh --scan) instead of target_resampled.*
#
# Each peer maps the source to the target sampled independently of it (make_pairs.py
# target_resampled.*: re-meshed from its level set in 3D, resampled by arc length in 2D), so it
# cannot read the correspondence off a shared vertex order; the error is |phi(v) - g(v)| over the
# source's vertices, in unit-box units of vdb_match's placement of the two shapes (margin 0.2:
# the union of their vertex boxes, largest side scaled to 0.6), so the numbers compare with
# `bench_accuracy.sh --resampled`. Parameters, fixed once for every pair (not tuned per pair):
#   BCPD  -w0 -l50 -b2 -g0.1 -ux -c1e-6 -n500 -r1 (the authors' Armadillo demo, with -g0.1 -ux,
#         which their README recommends for shapes already roughly aligned), and in 3D its
#         acceleration -J300 -K70 -p -f0.3 -DB,5000,0.02 as in that demo; X = target points,
#         Y = source points, the output y.txt = phi(Y) in the source's order, world units.
#   AMM   its defaults (radius 5, alpha 100, beta 10), source.obj -> target_resampled.obj; the
#         output mesh keeps the source's vertex order.
#   SyN   ANTs' antsRegistrationSyN.sh as its users run it: its three stages (rigid and affine
#         with MI, then SyN[0.1,3,0] with CC radius 4; its iterations, shrink factors and
#         smoothing) on the signed distances of the source (fixed) and of target_resampled
#         (moving), sampled by bench/accuracy/sdf_images.py on the nodes of vdb_match's level 7
#         in 3D, 9 in 2D (the resolution of elastix in compare_elastix.sh), without the script's
#         centre-of-mass initial transform (the shapes share the placement, and on signed
#         distances that centre moves the wrong way). antsApplyTransformsToPoints maps the
#         source's vertices by the forward transforms (Warp, then the affine): phi(v) = T(v).
#         Set ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS to choose its cores. (MeanSquares instead of
#         CC, tried once: 45 s instead of 13 minutes on the swirled creature, but far from
#         converged on the signed distances: error 16.3e-3 against 7.7e-3.)
#   elastix  B-spline registration of the same signed-distance images as SyN (fixed = source,
#         moving = target), with the parameters of bench/accuracy/elastix.sh, which
#         bench/compare_elastix.sh uses too (its side-by-side speed comparison, 3D); transformix
#         -def maps the source's vertices: phi(v) = T(v). Threads: -threads
#         $ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS when set, else elastix's default (all cores).
# Prints one row per pair and peer: err mean, err p95, wall seconds, peak memory (GNU time); for
# SyN and elastix also their residual, mean |d2(phi(v))| sampled in the target's image.
set -euo pipefail

die() { echo "compare_peers.sh: $*" >&2; exit 1; }
usage() { sed -n '/^# Usage:/,/^#   --out/p' "$0" | sed 's/^# \{0,1\}//'; }

PAIRS=all
BCPD=
AMM=
SYN=
ELASTIX=
OUT=
TARGET_NAME=target_resampled
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --scan) TARGET_NAME=target_scan; shift ;;
    --pairs|--bcpd|--amm|--syn|--elastix|--out)
      [ $# -ge 2 ] || die "$1 needs a value"
      case "$1" in
        --pairs) PAIRS=$2 ;; --bcpd) BCPD=$2 ;; --amm) AMM=$2 ;; --syn) SYN=$2 ;;
        --elastix) ELASTIX=$2 ;; --out) OUT=$2 ;;
      esac
      shift 2 ;;
    *) usage >&2; die "unknown argument $1" ;;
  esac
done

ROOT=$(cd "$(dirname "$0")/.." && pwd)
PYTHON=python3
[ -x /usr/bin/python3 ] && PYTHON=/usr/bin/python3
MAKE_PAIRS=$ROOT/bench/accuracy/make_pairs.py
[ -x /usr/bin/time ] || die "needs GNU time (apt-get install -y time)"
[ -z "$BCPD" ] || [ -x "$BCPD" ] || die "--bcpd $BCPD is not an executable"
[ -z "$AMM" ] || [ -x "$AMM" ] || die "--amm $AMM is not an executable"
if [ -n "$SYN" ]; then
  [ -x "$SYN" ] || die "--syn $SYN is not an executable"
  SYN_POINTS=$(dirname "$SYN")/antsApplyTransformsToPoints
  [ -x "$SYN_POINTS" ] || die "--syn: $SYN_POINTS not found (build that target of ANTs too)"
fi
if [ -n "$ELASTIX" ]; then
  [ -x "$ELASTIX" ] || die "--elastix $ELASTIX is not an executable"
  TRANSFORMIX=$(dirname "$ELASTIX")/transformix
  [ -x "$TRANSFORMIX" ] || die "--elastix: $TRANSFORMIX not found"
  source "$ROOT/bench/accuracy/elastix.sh"
  elastix_check || die "bad elastix parameters"
fi
if [ -n "$SYN$ELASTIX" ]; then  # the signed-distance images (bench/accuracy/sdf_images.py)
  "$PYTHON" -c 'import numpy, pyopenvdb' 2>/dev/null ||
    die "--syn and --elastix need numpy and pyopenvdb in $PYTHON (apt-get install -y python3-numpy python3-openvdb)"
fi
[ -n "$BCPD$AMM$SYN$ELASTIX" ] ||
  echo "compare_peers.sh: none of --bcpd, --amm, --syn, --elastix given: every peer is skipped"

source "$ROOT/bench/accuracy/ensure_pairs.sh"
output_dir peers
case "$PAIRS" in all|speed) PAIRS=$("$PYTHON" "$MAKE_PAIRS" --list "$PAIRS" | paste -sd, -) ;; esac
IFS=, read -r -a PAIR_LIST <<<"$PAIRS"

ensure_pairs "$OUT" "${PAIR_LIST[@]}" >/dev/null

# points FILE OUT: the vertices of an OBJ (v lines) or a polyline (x y lines), tab-separated.
points() {
  "$PYTHON" - "$1" "$2" <<'PY'
import sys
rows = []
for line in open(sys.argv[1]):
    parts = line.split()
    if not parts or parts[0].startswith("#"):
        continue
    if parts[0] == "v":
        rows.append(parts[1:4])
    elif parts[0][0].isdigit() or parts[0][0] in "+-.":
        rows.append(parts[:2])
open(sys.argv[2], "w").write("".join("\t".join(r) + "\n" for r in rows))
PY
}

# score PAIRDIR TARGET PHI_FILE PEER WALL RSS_KB: prints and appends one row.
score() {
  ACCURACY_DIR=$ROOT/bench/accuracy "$PYTHON" - "$@" "$OUT/peers.tsv" <<'PY'
import json, os, sys
import numpy as np
pair_dir, target, phi_file, peer, wall, rss, tsv = sys.argv[1:8]
sys.path.insert(0, os.environ["ACCURACY_DIR"])
from score import read_points  # noqa: E402  (bench/accuracy/score.py)
pair = json.load(open(os.path.join(pair_dir, "pair.json")))
dim = pair["dimension"]
source = read_points(os.path.join(pair_dir, "source." + ("obj" if dim == 3 else "polyline")), dim)
truth = read_points(os.path.join(pair_dir, "truth.xyz"), dim)
tgt = read_points(target, dim)
phi = read_points(phi_file, dim)
if len(phi) != len(source):
    sys.exit("compare_peers.sh: %s on %s returned %d points for %d source vertices"
             % (peer, pair["name"], len(phi), len(source)))
both = np.vstack([source, tgt])
scale = 0.6 / (both.max(axis=0) - both.min(axis=0)).max()  # vdb_match's placement, margin 0.2
err = np.linalg.norm(phi - truth, axis=1) * scale
motion = pair["motion"]["meanWorld"] * scale
print("%-21s %-7s %9.2e %9.2e %9.2e %8.1f %8.0f" % (pair["name"], peer, err.mean(),
      np.percentile(err, 95), motion, float(wall), int(rss) / 1024))
new = not os.path.exists(tsv)
with open(tsv, "a") as f:
    if new:
        f.write("pair\tdim\tpeer\terr_mean\terr_p95\tmotion_mean\twall_s\tpeak_mb\n")
    f.write("%s\t%d\t%s\t%.6g\t%.6g\t%.6g\t%s\t%.0f\n" % (pair["name"], dim, peer, err.mean(),
            np.percentile(err, 95), motion, wall, int(rss) / 1024))
PY
}

# syn_run DIM RUNDIR: antsRegistrationSyN.sh's three stages on RUNDIR/sdf (fixed = the source's
# signed distance, moving = the target's), then the source's vertices mapped by the forward
# transforms into RUNDIR/syn_phi.xyz (world units). Time and peak memory of both steps (the
# signed-distance images are not counted, as for elastix) in RUNDIR/syn.time.
syn_run() {
  local dim=$1 rd=$2 f m
  f=$rd/sdf/source_sdf.mhd
  m=$rd/sdf/target_sdf.mhd
  /usr/bin/time -f '%e %M' -o "$rd/syn.reg.time" "$SYN" --dimensionality "$dim" --float 1 \
    --collapse-output-transforms 1 --output "$rd/syn_" --interpolation Linear \
    --use-histogram-matching 0 --winsorize-image-intensities "[0.005,0.995]" \
    --transform "Rigid[0.1]" --metric "MI[$f,$m,1,32,Regular,0.25]" \
    --convergence "[1000x500x250x100,1e-6,10]" --shrink-factors 8x4x2x1 --smoothing-sigmas 3x2x1x0vox \
    --transform "Affine[0.1]" --metric "MI[$f,$m,1,32,Regular,0.25]" \
    --convergence "[1000x500x250x100,1e-6,10]" --shrink-factors 8x4x2x1 --smoothing-sigmas 3x2x1x0vox \
    --transform "SyN[0.1,3,0]" --metric "CC[$f,$m,1,4]" \
    --convergence "[100x70x50x20,1e-6,10]" --shrink-factors 8x4x2x1 --smoothing-sigmas 3x2x1x0vox \
    >"$rd/syn.log" 2>&1 || return 1
  /usr/bin/time -f '%e %M' -o "$rd/syn.map.time" "$SYN_POINTS" --dimensionality "$dim" \
    --input "$rd/sdf/source_points.csv" --output "$rd/syn_points.csv" \
    --transform "$rd/syn_1Warp.nii.gz" --transform "$rd/syn_0GenericAffine.mat" \
    >>"$rd/syn.log" 2>&1 || return 1
  image_peer_result "$rd" "$dim" syn
}

# elastix_run DIM RUNDIR: elastix's B-spline registration (bench/accuracy/elastix.sh) on
# RUNDIR/sdf, then transformix -def maps the source's vertices into RUNDIR/elastix_phi.xyz (world
# units). Time and peak memory of both steps in RUNDIR/elastix.time.
elastix_run() {
  local dim=$1 rd=$2 threads=()
  [ -z "${ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS:-}" ] || threads=(-threads "$ITK_GLOBAL_DEFAULT_NUMBER_OF_THREADS")
  mkdir -p "$rd/elastix" "$rd/transformix"
  elastix_parameters "$dim" "$rd/elastix/parameters.txt"
  /usr/bin/time -f '%e %M' -o "$rd/elastix.reg.time" "$ELASTIX" -f "$rd/sdf/source_sdf.mhd" \
    -m "$rd/sdf/target_sdf.mhd" -p "$rd/elastix/parameters.txt" -out "$rd/elastix" "${threads[@]}" \
    >"$rd/elastix.log" 2>&1 || return 1
  /usr/bin/time -f '%e %M' -o "$rd/elastix.map.time" "$TRANSFORMIX" -def "$rd/sdf/source_points.txt" \
    -tp "$rd/elastix/TransformParameters.0.txt" -out "$rd/transformix" "${threads[@]}" \
    >>"$rd/elastix.log" 2>&1 || return 1
  ACCURACY_DIR=$ROOT/bench/accuracy "$PYTHON" - "$rd" "$dim" <<'PY'
import os, sys
import numpy as np
sys.path.insert(0, os.environ["ACCURACY_DIR"])
from sdf_images import read_transformix_points  # noqa: E402  (bench/accuracy/sdf_images.py)
rd, dim = sys.argv[1], int(sys.argv[2])
np.savetxt(f"{rd}/elastix_points.csv", read_transformix_points(f"{rd}/transformix/outputpoints.txt", dim),
           delimiter=",", fmt="%.9g", header=",".join("xyz"[:dim]), comments="")
PY
  image_peer_result "$rd" "$dim" elastix
}

# image_peer_result RUNDIR DIM NAME: for an image peer's mapped points RUNDIR/NAME_points.csv
# (unit box, a header line, then x,y[,z] first on each line), writes RUNDIR/NAME_phi.xyz (world
# units), RUNDIR/NAME_residual.txt (mean |d2(phi(v))| sampled in the target's image, and h) and
# RUNDIR/NAME.time (the wall times of NAME.reg.time and NAME.map.time added up, the larger peak
# memory).
image_peer_result() {
  ACCURACY_DIR=$ROOT/bench/accuracy "$PYTHON" - "$1" "$2" "$3" <<'PY'
import json, os, sys
import numpy as np
rd, dim, name = sys.argv[1], int(sys.argv[2]), sys.argv[3]
place = json.load(open(f"{rd}/sdf/placement.json"))
unit = np.loadtxt(f"{rd}/{name}_points.csv", delimiter=",", skiprows=1, ndmin=2)[:, :dim]
np.savetxt(f"{rd}/{name}_phi.xyz", unit / place["scale"] + np.array(place["origin"]), fmt="%.9g")
# how closely T fits the target: |d2(T(v))| sampled in the target's image
sys.path.insert(0, os.environ["ACCURACY_DIR"])
from sdf_images import sample  # noqa: E402  (bench/accuracy/sdf_images.py)
header = dict(l.split(" = ", 1) for l in open(f"{rd}/sdf/target_sdf.mhd").read().splitlines())
n, h = int(header["DimSize"].split()[0]), float(header["ElementSpacing"].split()[0])
d2 = np.fromfile(f"{rd}/sdf/target_sdf.raw", np.float32).reshape((n,) * dim).transpose()
res = sample(d2, h, unit)
open(f"{rd}/{name}_residual.txt", "w").write("%.6g %.6g\n" % (np.abs(res).mean(), h))
reg, pts = (open(f"{rd}/{name}.{k}.time").read().split()[-2:] for k in ("reg", "map"))
open(f"{rd}/{name}.time", "w").write(
    "%.2f %d\n" % (float(reg[0]) + float(pts[0]), max(int(reg[1]), int(pts[1]))))
PY
}

# sdf_images PAIRDIR DIM RUNDIR: the signed-distance images of the pair in RUNDIR/sdf (level 7 in
# 3D, 9 in 2D), once per run directory.
sdf_images() {
  local level=7
  [ "$2" = 3 ] || level=9
  [ -f "$3/sdf/source_points.txt" ] && [ "$3/sdf/placement.json" -nt "$1/pair.json" ] \
      && [ "$(cat "$3/sdf/target_name" 2>/dev/null)" = "$TARGET_NAME" ] && return 0
  "$PYTHON" "$ROOT/bench/accuracy/sdf_images.py" --pair "$1" --level "$level" --out "$3/sdf" \
      --target "$TARGET_NAME" && echo "$TARGET_NAME" >"$3/sdf/target_name"
}

# image_peer NAME RUN PREFIX: an image peer on the current pair (the loop's p, pd, dim, rd and
# target): its signed-distance images, RUN DIM RUNDIR (syn_run, elastix_run), then its score row
# and its residual.
image_peer() {
  local name=$1 run=$2 prefix=$3 wall rss res h
  sdf_images "$pd" "$dim" "$rd" || die "sdf_images.py failed on $p"
  "$run" "$dim" "$rd" || { tail -n 5 "$rd/$prefix.log" >&2; die "$name failed on $p"; }
  read -r wall rss <"$rd/$prefix.time"
  score "$pd" "$target" "$rd/${prefix}_phi.xyz" "$name" "$wall" "$rss"
  read -r res h <"$rd/${prefix}_residual.txt"
  printf '%-21s %-7s residual mean |d2(phi(v))| %s (h = %s, unit box)\n' "$p" "$name" "$res" "$h"
}

rm -f "$OUT/peers.tsv"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
printf '%-21s %-7s %9s %9s %9s %8s %8s\n' pair peer "err mean" "err p95" motion "wall s" "peak MB"
for p in "${PAIR_LIST[@]}"; do
  pd=$OUT/pairs/$p
  dim=$("$PYTHON" -c 'import json,sys; print(json.load(open(sys.argv[1]))["dimension"])' "$pd/pair.json")
  if [ "$dim" = 3 ]; then ext=obj; else ext=polyline; fi
  target=$pd/$TARGET_NAME.$ext
  rd=$OUT/runs/$p
  mkdir -p "$rd"
  if [ -n "$BCPD" ]; then
    points "$target" "$rd/X.txt"
    points "$pd/source.$ext" "$rd/Y.txt"
    accel=()
    # shellcheck disable=SC2054  # -DB,5000,0.02 is one BCPD option
    [ "$dim" = 2 ] || accel=(-J300 -K70 -p -f0.3 -DB,5000,0.02)
    ( cd "$rd" && /usr/bin/time -f '%e %M' -o bcpd.time "$BCPD" -x X.txt -y Y.txt -w0.0 -l50 -b2.0 \
        -g0.1 -ux "${accel[@]}" -c1e-6 -n500 -r1 -o bcpd_ -sy >bcpd.log 2>&1 ) \
        || { tail -n 5 "$rd/bcpd.log" >&2; die "bcpd failed on $p"; }
    read -r wall rss <"$rd/bcpd.time"
    score "$pd" "$target" "$rd/bcpd_y.txt" BCPD "$wall" "$rss"
  fi
  if [ -n "$AMM" ]; then
    if [ "$dim" = 3 ]; then
      ( cd "$rd" && /usr/bin/time -f '%e %M' -o amm.time "$AMM" "$pd/source.obj" "$target" "$rd/amm_" 5 100 10 \
          >amm.log 2>&1 ) || { tail -n 5 "$rd/amm.log" >&2; die "AMM failed on $p"; }
      read -r wall rss <"$rd/amm.time"
      score "$pd" "$target" "$rd/amm_res.obj" AMM "$wall" "$rss"
    else
      printf '%-21s %-7s %s\n' "$p" AMM "skipped: 3D triangle meshes only"
    fi
  fi
  [ -z "$SYN" ] || image_peer SyN syn_run syn
  [ -z "$ELASTIX" ] || image_peer elastix elastix_run elastix
done
[ $KEEP = 0 ] || echo "results: $OUT/peers.tsv"
