#!/usr/bin/env bash
# CLI tests of `vdb_match apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse]`: usage, I/O and
# invalid-input errors with their exit codes and no output file left behind; a level set carried
# by phi equals match's deformed.vdb; a quad OBJ with UVs keeps its topology and comes back with
# --inverse; PLY attributes; point files; 2D curves and slices; fog and vector grids.
# Usage: test_cli_apply.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_apply.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_apply.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-apply.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"

find_python "pyopenvdb, numpy"

# pycheck NAME SCRIPT ARGS...: runs a python check, which prints 'ok' or a reason.
pycheck() {
    local name=$1
    shift
    count=$((count + 1))
    local result
    result=$("$PYTHON" - "$@" 2>&1)
    if [ "$result" = "ok" ]; then echo "ok   $name"; else fail "$name: $result"; fi
}

# no_output NAME FILE: the failed command left nothing at FILE.
no_output() {
    count=$((count + 1))
    if [ -e "$2" ] || ls "$(dirname "$2")"/.*tmp* >/dev/null 2>&1; then
        fail "$1: an output file was left at $2"
    else
        echo "ok   $1"
    fi
}

# Deformations to apply: a 3D match (sphere -> ellipsoid) and a 2D one (figures), coarse.
"$VDB_MATCH" "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/m3" --levels 3..5 --quiet >/dev/null ||
    { echo "FAIL setup: 3D match failed"; exit 1; }
"$VDB_MATCH" "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/m2" --levels 4..6 --quiet >/dev/null ||
    { echo "FAIL setup: 2D match failed"; exit 1; }
PHI3="$SCRATCH/m3/deformation.vdb"
PHI2="$SCRATCH/m2/deformation.vdb"

# A quad cube with UVs, normals, groups and materials, inside the 3D domain.
cat >"$SCRATCH/cube.obj" <<'EOF'
# a quad cube
mtllib cube.mtl
o cube
v -0.3 -0.3 -0.3
v 0.3 -0.3 -0.3
v 0.3 0.3 -0.3
v -0.3 0.3 -0.3
v -0.3 -0.3 0.3
v 0.3 -0.3 0.3
v 0.3 0.3 0.3
v -0.3 0.3 0.3
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 0 1 0
vn -1 0 0
vn 1 0 0
g sides
usemtl skin
s 1
f 1/1/1 4/2/1 3/3/1 2/4/1
f 5/1/2 6/2/2 7/3/2 8/4/2
f 1/1/3 2/2/3 6/3/3 5/4/3
f 4/1/4 8/2/4 7/3/4 3/4/4
f 1/1/5 5/2/5 8/3/5 4/4/5
f 2/1/6 3/2/6 7/3/6 6/4/6
EOF
printf 'x,y,z,label\n0.1,0.2,0.05,"tip, left"\n-0.2,0.0,0.1,base\n# a comment\n0.5,0.5,0.5,far\n' >"$SCRATCH/points.csv"
printf 'x,y,label\n0.1,0.2,a\n' >"$SCRATCH/nz.csv"
printf 'v 0 0\n' >"$SCRATCH/bad.obj"
printf 'not a vdb file\n' >"$SCRATCH/garbage.vdb"
"$PYTHON" - "$SCRATCH" <<'EOF' || { echo "FAIL setup: python could not write the test grids"; exit 1; }
import sys, pyopenvdb as vdb
d = sys.argv[1]
g = vdb.BoolGrid()
g.name = "mask"
g.getAccessor().setValueOn((1, 2, 3), True)
vdb.write(d + "/mask.vdb", [g])
# A fog block and a vector grid in the middle of the 3D domain.
fog = vdb.FloatGrid(0.0)
fog.name = "density"
fog.gridClass = vdb.GridClass.FOG_VOLUME
fog.transform = vdb.createLinearTransform(voxelSize=0.05)
vel = vdb.Vec3SGrid()
vel.name = "vel"
vel.transform = vdb.createLinearTransform(voxelSize=0.05)
fa, va = fog.getAccessor(), vel.getAccessor()
for i in range(-6, 7):
    for j in range(-6, 7):
        for k in range(-6, 7):
            fa.setValueOn((i, j, k), 1.0 + 0.1 * i)
            va.setValueOn((i, j, k), (1.0, 2.0, 3.0))
vdb.write(d + "/fog.vdb", [fog, vel])
EOF

# ---------------------------------------------------------------- usage (1)
check help 0 'Usage: vdb_match apply' '' -- apply --help
check main-help-lists-apply 0 'apply DEFORMATION.vdb INPUT' '' -- --help
check missing-output 1 '' 'missing the output file' -- apply "$PHI3" "$SCRATCH/cube.obj"
check one-argument 1 '' 'expects DEFORMATION.vdb INPUT' -- apply "$PHI3" -o "$SCRATCH/x.obj"
check format-mismatch 1 '' "output must have the input's format" -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/x.ply"
check unknown-extension 1 '' 'cannot tell what' -- apply "$PHI3" "$SCRATCH/cube.abc" -o "$SCRATCH/x.abc"
check attributes-obj 1 '' 'needs a PLY mesh' -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --attributes
check target-alone 1 '' 'add --attributes' -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --target "$ELLIPSOID"
check overwrite-input 1 '' 'would overwrite' -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/cube.obj"
check unknown-option 1 '' "unknown option '--frobnicate'" -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --frobnicate
no_output usage-no-output "$SCRATCH/x.obj"

# ---------------------------------------------------------------- I/O (2)
check missing-deformation 2 '' 'does not exist' -- apply "$SCRATCH/none.vdb" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj"
check missing-input 2 '' 'does not exist' -- apply "$PHI3" "$SCRATCH/none.obj" -o "$SCRATCH/x.obj"
check garbage-deformation 2 '' 'cannot read' -- apply "$SCRATCH/garbage.vdb" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --quiet
check output-dir-missing 2 '' '' -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/no/such/dir/x.obj" --quiet
no_output io-no-output "$SCRATCH/x.obj"

# ---------------------------------------------------------------- invalid input (3)
check not-a-deformation 3 '' "no grid named 'displacement'" -- apply "$SPHERE" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --quiet
check bad-mesh 3 '' '' -- apply "$PHI3" "$SCRATCH/bad.obj" -o "$SCRATCH/x.obj" --quiet
check missing-z 3 '' "column 'z'" -- apply "$PHI3" "$SCRATCH/nz.csv" -o "$SCRATCH/x.csv" --quiet
check bool-grid 3 '' "grid 'mask' .* holds bool values" -- apply "$PHI3" "$SCRATCH/mask.vdb" -o "$SCRATCH/x.vdb" --quiet
check no-such-grid 3 '' "no grid named 'nope'" -- apply "$PHI3" "$SCRATCH/fog.vdb" -o "$SCRATCH/x.vdb" --grid nope --quiet
check curves-3d 3 '' 'deformation is 3D' -- apply "$PHI3" "$FIGURE_A" -o "$SCRATCH/x.polyline" --quiet
check mesh-2d-deformation 3 '' 'the deformation is 2D .* but the mesh is 3D' -- apply "$PHI2" "$SCRATCH/cube.obj" -o "$SCRATCH/x.obj" --quiet
check grid-3d-2d-deformation 3 '' 'is 3D but the deformation is 2D' -- apply "$PHI2" "$SPHERE" -o "$SCRATCH/x.vdb" --quiet
check slice-3d 3 '' '2D slice' -- apply "$PHI3" "$ASSETS/figure_a_slice.vdb" -o "$SCRATCH/x.vdb" --quiet
no_output invalid-no-output "$SCRATCH/x.vdb"
no_output invalid-no-output-obj "$SCRATCH/x.obj"
no_output invalid-no-output-csv "$SCRATCH/x.csv"

# ---------------------------------------------------------------- level set: same as deformed.vdb
check level-set 0 'level set rebuilt' 'carrying grid' -- apply "$PHI3" "$SPHERE" -o "$SCRATCH/sphere_moved.vdb"
pycheck level-set-equals-deformed "$SCRATCH/sphere_moved.vdb" "$SCRATCH/m3/deformed.vdb" <<'EOF'
import sys, numpy as np, pyopenvdb as vdb
a = vdb.read(sys.argv[1], "surface"); b = vdb.read(sys.argv[2], "surface")
# Both are the distance of phi(M1) rebuilt on the source's transform; compare on a's active voxels.
ba = b.getConstAccessor()
worst = 0.0; n = 0
for it in a.citerOnValues():
    v, on = ba.probeValue(it.min)
    if on and abs(it.value) < 2 * a.transform.voxelSize()[0]:
        worst = max(worst, abs(it.value - v)); n += 1
h = a.transform.voxelSize()[0]
print("ok" if n > 100 and worst < 0.05 * h else f"max difference {worst} over {n} voxels (h = {h})")
EOF

# ---------------------------------------------------------------- mesh source: same as deformed.obj
check match-mesh-source 0 '' '' -- "$SCRATCH/cube.obj" "$ELLIPSOID" -o "$SCRATCH/mc" --levels 3..4 --quiet
check apply-mesh-source 0 '' '' -- apply "$SCRATCH/mc/deformation.vdb" "$SCRATCH/cube.obj" -o "$SCRATCH/cube_applied.obj" --quiet
pycheck apply-equals-deformed-obj "$SCRATCH/cube_applied.obj" "$SCRATCH/mc/deformed.obj" <<'EOF'
import sys, numpy as np
def read(p):
    return np.array([[float(t) for t in l.split()[1:4]] for l in open(p) if l.startswith("v ")])
a, b = read(sys.argv[1]), read(sys.argv[2])
# deformed.obj is phi in double; the grid stores single precision: agree to float rounding.
err = np.abs(a - b).max() if a.shape == b.shape else float("inf")
print("ok" if err < 1e-6 * max(1.0, np.abs(b).max()) else f"max difference {err} ({a.shape} vs {b.shape})")
EOF

# ---------------------------------------------------------------- quad OBJ: topology kept, round trip
check obj-forward 0 '8 vertices and 6 normals moved by phi' '' -- apply "$PHI3" "$SCRATCH/cube.obj" -o "$SCRATCH/cube_fwd.obj"
check obj-inverse 0 'moved by phi\^-1' '' -- apply "$PHI3" "$SCRATCH/cube_fwd.obj" -o "$SCRATCH/cube_back.obj" --inverse --quiet
count=$((count + 1))
if diff <(grep -v '^v ' "$SCRATCH/cube.obj" | grep -v '^vn ') <(grep -v '^v ' "$SCRATCH/cube_fwd.obj" | grep -v '^vn '); then
    echo "ok   obj-keeps-faces-uvs-groups"
else
    fail "obj-keeps-faces-uvs-groups: lines other than v/vn changed"
fi
pycheck obj-round-trip "$SCRATCH/cube.obj" "$SCRATCH/cube_back.obj" "$SCRATCH/cube_fwd.obj" <<'EOF'
import sys, numpy as np
def read(p, tag):
    return np.array([[float(t) for t in l.split()[1:4]] for l in open(p) if l.split()[:1] == [tag]])
a, b, f = read(sys.argv[1], "v"), read(sys.argv[2], "v"), read(sys.argv[3], "v")
moved = np.abs(f - a).max()
err = np.abs(b - a).max()
n = read(sys.argv[3], "vn")
unit = np.abs(np.linalg.norm(n, axis=1) - 1).max()
print("ok" if err < 1e-9 and moved > 1e-3 and unit < 1e-9 else f"round trip {err}, moved {moved}, |n|-1 {unit}")
EOF

# ---------------------------------------------------------------- PLY attributes
"$PYTHON" - "$SCRATCH/m3/deformed.obj" "$SCRATCH/target_side.ply" <<'EOF'
import sys, struct
v, f = [], []
for line in open(sys.argv[1]):
    t = line.split()
    if t[:1] == ["v"]: v.append([float(x) for x in t[1:4]])
    if t[:1] == ["f"]: f.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
with open(sys.argv[2], "wb") as out:
    out.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\nelement face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
    for p in v: out.write(struct.pack("<3f", *p))
    for t in f: out.write(struct.pack("<B3i", 3, *t))
EOF
check ply-attributes 0 'attributes det_jacobian area_stretch displacement residual' '' -- apply "$PHI3" "$SCRATCH/target_side.ply" -o "$SCRATCH/source_side.ply" --inverse --attributes --target "$SPHERE" --quiet
pycheck ply-attribute-values "$SCRATCH/source_side.ply" "$SCRATCH/m3/report.json" <<'EOF'
import sys, struct, json, numpy as np
data = open(sys.argv[1], "rb").read()
head, body = data.split(b"end_header\n", 1)
names = [l.split()[-1].decode() for l in head.splitlines() if l.startswith(b"property float")]
n = int([l for l in head.splitlines() if l.startswith(b"element vertex")][0].split()[-1])
want = ["x", "y", "z", "det_jacobian", "area_stretch", "displacement", "residual"]
if names != want: print(f"properties {names}"); sys.exit()
rows = np.frombuffer(body[: n * 4 * len(names)], dtype="<f4").reshape(n, len(names))
det, stretch, disp, res = rows[:, 3], rows[:, 4], rows[:, 5], rows[:, 6]
# The sphere (r 0.5) was stretched to an ellipsoid: going back shrinks (det of the inverse < 1 on average).
bad = []
if not (det > 0).all(): bad.append("det <= 0")
if not (0.2 < stretch.mean() < 1.5): bad.append(f"area stretch mean {stretch.mean()}")
if not (disp.max() > 0.01): bad.append(f"displacement max {disp.max()}")
# The carried surface lies on M1 (the sphere) up to the match's residual.
h = 2.0 ** -5
if not (res.mean() < 0.1): bad.append(f"residual mean {res.mean()}")
print("ok" if not bad else "; ".join(bad))
EOF

# ---------------------------------------------------------------- points
check points 0 '3 points moved by phi' '' -- apply "$PHI3" "$SCRATCH/points.csv" -o "$SCRATCH/points_fwd.csv"
check points-back 0 '' '' -- apply "$PHI3" "$SCRATCH/points_fwd.csv" -o "$SCRATCH/points_back.csv" --inverse --quiet
pycheck points-kept "$SCRATCH/points.csv" "$SCRATCH/points_fwd.csv" "$SCRATCH/points_back.csv" <<'EOF'
import sys, csv
rows = [list(csv.reader(l for l in open(p) if not l.startswith("#"))) for p in sys.argv[1:]]
a, f, b = rows
ok = [r[3] for r in a] == [r[3] for r in f] and a[0] == f[0] and "# a comment\n" in open(sys.argv[2]).read()
err = max(abs(float(x) - float(y)) for ra, rb in zip(a[1:], b[1:]) for x, y in zip(ra[:3], rb[:3]))
moved = max(abs(float(x) - float(y)) for ra, rf in zip(a[1:], f[1:]) for x, y in zip(ra[:3], rf[:3]))
print("ok" if ok and err < 1e-9 and moved > 1e-3 else f"kept {ok}, round trip {err}, moved {moved}")
EOF

# ---------------------------------------------------------------- 2D: curves and slices
check curves-2d 0 'curve vertices moved by phi' '' -- apply "$PHI2" "$FIGURE_A" -o "$SCRATCH/figure_moved.polyline"
check slice-2d 0 'level set rebuilt' '' -- apply "$PHI2" "$ASSETS/figure_a_slice.vdb" -o "$SCRATCH/figure_moved.vdb" --quiet
check slice-2d-matches 0 '' '' -- energy "$SCRATCH/figure_moved.vdb" "$ASSETS/figure_b_slice.vdb" --level 6 --quiet

# ---------------------------------------------------------------- fog and vector grids
check fog 0 'density \(resampled\), vel \(resampled\)' '' -- apply "$PHI3" "$SCRATCH/fog.vdb" -o "$SCRATCH/fog_fwd.vdb" --quiet
check fog-one-grid 0 'vel \(resampled\)' '' -- apply "$PHI3" "$SCRATCH/fog.vdb" -o "$SCRATCH/vel_back.vdb" --grid vel --inverse --quiet
pycheck fog-values "$SCRATCH/fog_fwd.vdb" <<'EOF'
import sys, pyopenvdb as vdb
# Values move with the points; at the block's edge trilinear sampling blends with the
# background 0, so the range is [0, 1.6] (the input's is [0.4, 1.6]).
fog = vdb.read(sys.argv[1], "density"); vel = vdb.read(sys.argv[1], "vel")
lo, hi = fog.evalMinMax()
vlo, vhi = vel.evalMinMax()
ok = (fog.gridClass == vdb.GridClass.FOG_VOLUME and fog.activeVoxelCount() > 1000
      and 0.0 <= lo and abs(hi - 1.6) < 0.05 and abs(vhi[2] - 3.0) < 1e-5
      and fog["vdbmatch_direction"] == "forward")
print("ok" if ok else f"class {fog.gridClass}, {fog.activeVoxelCount()} voxels, range {lo}..{hi}, vel max {vhi}")
EOF

echo "$((count - failures))/$count checks passed"
[ "$failures" -eq 0 ]
