#!/usr/bin/env python3
"""Signed-distance images of a pair's two shapes, for the image-registration peers
(bench/compare_peers.sh --syn and --elastix, bench/compare_elastix.sh).

    sdf_images.py --pair PAIRDIR --level L --out DIR [--band X] [--target NAME]

Both shapes (source.obj / source.polyline and target_resampled.*, or NAME.* with --target) are
placed in the unit box as
vdb_match places them (margin 0.2: the union of their vertex boxes, largest side scaled to 0.6
and centred), and sampled on the nodes of level L: (2^L + 1)^d pixels of size h = 2^-L covering
[0, 1]^d, the resolution of vdb_match's level L. Distances are in unit-box lengths, negative
inside, exact up to --band (default 0.3) and clamped beyond (only near the corners of the box).
Writes into DIR:
  source_sdf.mhd/.raw, target_sdf.mhd/.raw   MetaImage, float, origin 0, spacing h, identity
                                             directions: physical coordinates = unit-box ones
  source_points.csv                          the source's vertices in unit-box coordinates, in
                                             ANTs' point format (x,y[,z],t,label,comment)
  source_points.txt                          the same, in transformix's input point format
  placement.json                             {"origin": [...], "scale": s}: unit = s (world - origin)
3D distances come from OpenVDB's mesh-to-volume (pyopenvdb); 2D ones are exact distances to the
closed polyline's segments, signed by the even-odd rule.
"""

import argparse
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points  # noqa: E402  (bench/accuracy/score.py)

MARGIN = 0.2


def read_obj(path):
    """Vertices and fan-triangulated faces of an OBJ."""
    pts, tris = [], []
    with open(path) as f:
        for line in f:
            t = line.split("#")[0].split()
            if not t:
                continue
            if t[0] == "v":
                pts.append([float(x) for x in t[1:4]])
            elif t[0] == "f":
                idx = [int(x.split("/")[0]) for x in t[1:]]
                idx = [i - 1 if i > 0 else len(pts) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    tris.append([idx[0], idx[k], idx[k + 1]])
    return np.array(pts, float), np.array(tris, np.int32)


def read_polyline(path):
    """Closed curves of a polyline file: a list of (n, 2) arrays."""
    curves, cur = [], []
    with open(path) as f:
        for line in f:
            t = line.split("#")[0].split()
            if not t:
                if cur:
                    curves.append(np.array(cur, float))
                    cur = []
                continue
            cur.append([float(t[0]), float(t[1])])
    if cur:
        curves.append(np.array(cur, float))
    return curves


def placement(a, b):
    """vdb_match's placement of two point sets: unit = scale * (world - origin)."""
    both = np.vstack([a, b])
    lo, hi = both.min(axis=0), both.max(axis=0)
    scale = (1.0 - 2.0 * MARGIN) / (hi - lo).max()
    origin = (lo + hi) / 2.0 - 0.5 / scale  # the shapes' box centred in the unit box
    return origin, scale


def sdf_polyline(curves, n, h, chunk=4096):
    """a[i, j] = signed distance of the node (i, j) h to the closed curves (negative inside)."""
    seg_a = np.vstack(curves)
    seg_b = np.vstack([np.roll(c, -1, axis=0) for c in curves])
    ab = seg_b - seg_a
    ab2 = np.maximum((ab * ab).sum(axis=1), 1e-300)
    ii, jj = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    p = np.stack([ii.ravel(), jj.ravel()], axis=1) * h
    dist = np.empty(len(p))
    inside = np.zeros(len(p), bool)
    for s in range(0, len(p), chunk):
        q = p[s:s + chunk]
        ap = q[:, None, :] - seg_a[None, :, :]
        t = np.clip((ap * ab[None]).sum(axis=2) / ab2[None], 0.0, 1.0)
        d = ap - t[..., None] * ab[None]
        dist[s:s + chunk] = np.sqrt((d * d).sum(axis=2).min(axis=1))
        # even-odd rule: count the segments crossed by the ray from q towards +x
        ya, yb = seg_a[None, :, 1], seg_b[None, :, 1]
        crosses = (ya > q[:, 1:2]) != (yb > q[:, 1:2])
        with np.errstate(divide="ignore", invalid="ignore"):
            x = seg_a[None, :, 0] + (q[:, 1:2] - ya) / (yb - ya) * ab[None, :, 0]
        inside[s:s + chunk] = (crosses & (x > q[:, 0:1])).sum(axis=1) % 2 == 1
    return np.where(inside, -dist, dist).reshape(n, n)


def sdf_mesh(pts, tris, n, h, band):
    import pyopenvdb as vdb

    grid = vdb.FloatGrid.createLevelSetFromPolygons(
        pts.astype(np.float32), triangles=tris, transform=vdb.createLinearTransform(h),
        halfWidth=float(np.ceil(band / h)) + 2.0)
    a = np.empty((n, n, n), np.float32)
    grid.copyToArray(a, ijk=(0, 0, 0))
    return a


def sample(a, h, unit):
    """Multilinear interpolation of a[i, j(, k)], the values at the nodes (i, j(, k)) h, at the
    points unit (m, d); points outside the image are clamped to it."""
    n, dim = a.shape[0], a.ndim
    x = np.clip(unit / h, 0.0, n - 1 - 1e-9)
    i = np.floor(x).astype(int)
    f = x - i
    value = 0.0
    for corner in np.ndindex(*(2,) * dim):
        w = np.prod([f[:, k] if c else 1 - f[:, k] for k, c in enumerate(corner)], axis=0)
        value = value + w * a[tuple(i[:, k] + c for k, c in enumerate(corner))]
    return value


def write_mhd(path, a, h):
    """MetaImage, x fastest: a[i, j(, k)] is written in (k, j, i) C order."""
    dim = a.ndim
    raw = os.path.splitext(path)[0] + ".raw"
    np.ascontiguousarray(a.astype(np.float32).transpose(*reversed(range(dim)))).tofile(raw)
    eye = " ".join("1" if r == c else "0" for r in range(dim) for c in range(dim))
    with open(path, "w") as f:
        f.write(f"ObjectType = Image\nNDims = {dim}\nBinaryData = True\n"
                "BinaryDataByteOrderMSB = False\nCompressedData = False\n"
                f"TransformMatrix = {eye}\nOffset = {' '.join(['0'] * dim)}\n"
                f"CenterOfRotation = {' '.join(['0'] * dim)}\n"
                f"ElementSpacing = {' '.join([repr(h)] * dim)}\n"
                f"DimSize = {' '.join([str(a.shape[0])] * dim)}\n"
                f"ElementType = MET_FLOAT\nElementDataFile = {os.path.basename(raw)}\n")


def write_transformix_points(path, unit):
    """transformix's input point file (-def): "point", the count, then one point per line."""
    with open(path, "w") as f:
        f.write(f"point\n{len(unit)}\n")
        f.writelines(" ".join(repr(float(c)) for c in p) + "\n" for p in unit)


def read_transformix_points(path, dim):
    """The mapped points (OutputPoint) of transformix -def's outputpoints.txt, (m, dim)."""
    num = r"([-+0-9.eEinfINFaA]+)"
    pattern = re.compile(r"OutputPoint = \[\s*" + r"\s+".join([num] * dim))
    return np.array([[float(c) for c in pattern.search(line).groups()] for line in open(path)
                     if "OutputPoint" in line]).reshape(-1, dim)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", required=True)
    ap.add_argument("--level", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--band", type=float, default=0.3)
    ap.add_argument("--target", default="target_resampled",
                    help="the target file's name in the pair, without extension (default "
                         "target_resampled; target_scan for compare_peers.sh --scan)")
    args = ap.parse_args()
    if not 3 <= args.level <= 10:
        sys.exit("sdf_images.py: --level must be in 3..10")
    dim = json.load(open(os.path.join(args.pair, "pair.json")))["dimension"]
    ext = "obj" if dim == 3 else "polyline"
    src_file = os.path.join(args.pair, "source." + ext)
    tgt_file = os.path.join(args.pair, args.target + "." + ext)
    src_pts, tgt_pts = read_points(src_file, dim), read_points(tgt_file, dim)
    origin, scale = placement(src_pts, tgt_pts)
    n, h = 2 ** args.level + 1, 2.0 ** -args.level
    os.makedirs(args.out, exist_ok=True)
    for name, path in (("source", src_file), ("target", tgt_file)):
        if dim == 3:
            pts, tris = read_obj(path)
            a = sdf_mesh(scale * (pts - origin), tris, n, h, args.band)
        else:
            a = sdf_polyline([scale * (c - origin) for c in read_polyline(path)], n, h)
        write_mhd(os.path.join(args.out, f"{name}_sdf.mhd"), np.clip(a, -args.band, args.band), h)
    unit = scale * (src_pts - origin)
    axes = "xyz"[:dim]
    with open(os.path.join(args.out, "source_points.csv"), "w") as f:
        f.write(",".join(axes) + ",t,label,comment\n")
        f.writelines(",".join(repr(float(c)) for c in p) + ",0,0,0\n" for p in unit)
    write_transformix_points(os.path.join(args.out, "source_points.txt"), unit)
    with open(os.path.join(args.out, "placement.json"), "w") as f:
        json.dump({"origin": origin.tolist(), "scale": scale}, f)


if __name__ == "__main__":
    main()
