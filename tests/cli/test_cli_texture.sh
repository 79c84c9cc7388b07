#!/usr/bin/env bash
# CLI tests of `vdb_match texture PHI.vdb --source M1 [--inverse PSI.vdb] [--target M2] -o OUTDIR`:
# usage, I/O and dimension errors with their exit codes; end-to-end runs on the 2D figure pair
# and the 3D sphere/ellipsoid pair (match both ways at coarse levels, then texture) whose PNGs
# are decoded and checked to be non-blank and whose PLY headers are checked.
# Usage: test_cli_texture.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_texture.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_texture.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-texture.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT
PYTHON=/usr/bin/python3
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3

source "$(dirname "$0")/common.sh"


# pngs_nonblank FILE...: each is a PNG with several colours and a visible share of non-white
# pixels (decoded with the standard library: zlib and the PNG row filters).
pngs_nonblank() {
    "$PYTHON" - "$@" <<'PY'
import struct, sys, zlib
def decode(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path + ": not a PNG"
    pos, idat = 8, b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    assert depth == 8 and ctype in (2, 6), (path, depth, ctype)
    bpp = 3 if ctype == 2 else 4
    raw, stride, rows, prev = zlib.decompress(idat), w * bpp, [], bytearray(w * bpp)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, bpp, rows
for path in sys.argv[1:]:
    w, h, bpp, rows = decode(path)
    colours, ink = set(), 0
    for line in rows[::2]:
        for x in range(0, w, 2):
            px = bytes(line[x * bpp:x * bpp + 3])
            colours.add(px)
            ink += px != b"\xff\xff\xff"
    share = ink / ((len(rows[::2])) * len(range(0, w, 2)))
    assert len(colours) >= 8 and share > 0.01, (path, len(colours), share)
PY
}

# ply_ok FILE: a binary little-endian PLY with coloured vertices and faces.
ply_ok() {
    head -c 400 "$1" | grep -aq '^format binary_little_endian 1.0' &&
        head -c 400 "$1" | grep -aq '^property uchar red' &&
        head -c 400 "$1" | grep -aEq '^element vertex [1-9]' &&
        head -c 400 "$1" | grep -aEq '^element face [1-9]'
}

# ---------------------------------------------------------------- the deformations
check match-ab 0 '' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/ab" --levels 4..5 --quiet
check match-ba 0 '' '' -- "$FIGURE_B" "$FIGURE_A" -o "$SCRATCH/ba" --levels 4..5 --quiet
check match-3d 0 '' '' -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/se" --levels 3..4 --quiet
check match-3d-back 0 '' '' -- "$ELLIPSOID" "$SPHERE" -o "$SCRATCH/es" --levels 3..4 --quiet
touch "$SCRATCH/afile"

# ---------------------------------------------------------------- usage (1)
check help 0 'texture PHI.vdb' '' -- texture --help
check no-source 1 '' 'missing the source' -- texture "$SCRATCH/ab/deformation.vdb" -o "$SCRATCH/x"
check no-output 1 '' 'missing the output directory' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A"
check bad-pattern 1 '' '--pattern expects' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" -o "$SCRATCH/x" --pattern dots
check bad-size 1 '' '--size must be' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" -o "$SCRATCH/x" --size 3
check two-phis 1 '' 'texture expects PHI.vdb' -- texture "$SCRATCH/ab/deformation.vdb" "$SCRATCH/ba/deformation.vdb" --source "$FIGURE_A" -o "$SCRATCH/x"

# ---------------------------------------------------------------- I/O (2)
check missing-phi 2 '' '' -- texture "$SCRATCH/none.vdb" --source "$FIGURE_A" -o "$SCRATCH/x" --quiet
check missing-source 2 '' '' -- texture "$SCRATCH/ab/deformation.vdb" --source "$SCRATCH/none.polyline" -o "$SCRATCH/x" --quiet
check missing-inverse 2 '' '' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" --inverse "$SCRATCH/none.vdb" -o "$SCRATCH/x" --quiet
check outdir-is-file 2 '' 'output directory' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" -o "$SCRATCH/afile" --quiet

# ---------------------------------------------------------------- dimension mismatch (3)
check dim-source 3 '' '2D|3D' -- texture "$SCRATCH/ab/deformation.vdb" --source "$SPHERE" -o "$SCRATCH/x" --quiet
check dim-inverse 3 '' '2D|3D' -- texture "$SCRATCH/se/deformation.vdb" --source "$SPHERE" --inverse "$SCRATCH/ba/deformation.vdb" -o "$SCRATCH/x" --quiet
check dim-target 3 '' '2D|3D' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" --target "$ELLIPSOID" -o "$SCRATCH/x" --quiet
[ -e "$SCRATCH/x/source.png" ] && fail "an input error left outputs in $SCRATCH/x"

# ---------------------------------------------------------------- 2D end to end (0)
check texture-2d 0 'summary.png' '' -- texture "$SCRATCH/ab/deformation.vdb" --source "$FIGURE_A" \
    --inverse "$SCRATCH/ba/deformation.vdb" --target "$FIGURE_B" -o "$SCRATCH/tex2" --size 200 --quiet
count=$((count + 1))
if pngs_nonblank "$SCRATCH"/tex2/{source,deformed,roundtrip,summary}.png &&
    grep -q '^l ' "$SCRATCH/tex2/deformed.obj" && grep -q '^l ' "$SCRATCH/tex2/roundtrip.obj"; then
    echo "ok   texture-2d outputs"
else
    fail "texture-2d outputs"
fi
for pattern in stripes position; do
    check "texture-2d-$pattern" 0 'summary.png' '' -- texture "$SCRATCH/ab/deformation.vdb" \
        --source "$FIGURE_A" -o "$SCRATCH/tex2-$pattern" --pattern "$pattern" --size 100 --quiet
done
[ -e "$SCRATCH/tex2-stripes/roundtrip.png" ] && fail "roundtrip.png written without --inverse"

# ---------------------------------------------------------------- 3D end to end (0)
check texture-3d 0 'summary.png' '' -- texture "$SCRATCH/se/deformation.vdb" --source "$SPHERE" \
    --inverse "$SCRATCH/es/deformation.vdb" --target "$ELLIPSOID" -o "$SCRATCH/tex3" --size 120 --quiet
count=$((count + 1))
if pngs_nonblank "$SCRATCH"/tex3/{source,deformed,roundtrip,target,summary}.png &&
    ply_ok "$SCRATCH/tex3/source.ply" && ply_ok "$SCRATCH/tex3/deformed.ply" &&
    ply_ok "$SCRATCH/tex3/roundtrip.ply"; then
    echo "ok   texture-3d outputs"
else
    fail "texture-3d outputs"
fi
cat <(ls -A "$SCRATCH/tex3") <(ls -A "$SCRATCH/tex2") | grep -q "\.tmp" && fail "temporary files left in the output directory"

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
