#!/usr/bin/env python3
"""A rigid segment of a 2D limb between two joints, fitted from M1 to M2, as landmark pairs.

A measurement prototype (docs/results.md, "True correspondences on the two 2D motions left"):
the rigid limbs (vdbmatch/geometry/RigidLimbs.h) fit a limb from its tip; this fits a segment
further in, e.g. a thigh between the knee and the hip. On each closed polyline: the arc length
s from the tip (the lowest vertex on one side of x = 0, as a foot); the segment, the vertices of
that side with LO <= s < HI (world units); and the rigid motion that carries M1's segment onto
M2's by trimmed closest points made both ways at once (point to point, the farthest (1 - trim)
of the pairs left out). Writes every EVERY-th segment vertex of M1 and its image under that
motion, for `vdb_match match --landmarks A.csv B.csv`.

Usage: segment_fit.py SOURCE.polyline TARGET.polyline --lo LO --hi HI --out-source A.csv
           --out-target B.csv [--sides +1,-1] [--every N] [--iterations N] [--trim F] [--hop H]
  --hop H   measure s over chords joining each vertex to the next H (default 1: the arc length)
Prints per side the fitted angle (degrees, counter-clockwise) and the mean distance of the kept
pairs (world units). Arc length is the length along the outline: on a noisy scan it runs longer
than on the shape it samples (--hop 3 measures it over chords, as the rigid limbs do).
Exit status 0, or 1 with a message.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points  # noqa: E402  (the benchmark's one reader of vertex files)


def arc_length_from(curve, i0, hop=1):
    """Length along the closed curve from vertex i0, the shorter way round: with hop 1 the arc
    length; with hop H the shortest path over chords joining each vertex to the next H (as the
    rigid limbs' geodesics, RigidLimbs.h: on a noisy scan the arc length adds up its zigzag)."""
    n = len(curve)
    out = []
    for sign in (+1, -1):
        d = np.full(n, np.inf)
        d[i0] = 0.0
        for k in range(n):
            i = (i0 + sign * k) % n
            for h in range(1, hop + 1):
                if k + h >= n:
                    break
                j = (i0 + sign * (k + h)) % n
                d[j] = min(d[j], d[i] + np.linalg.norm(curve[j] - curve[i]))
        out.append(d)
    return np.minimum(out[0], out[1])


def closest(p, q):
    """Index in q of the closest point of each p (brute force: segments are small)."""
    return np.linalg.norm(p[:, None, :] - q[None, :, :], axis=2).argmin(1)


def fit_rigid(a, b, iterations=30, trim=0.9):
    """R, t carrying the points a onto the points b, and the mean distance of the kept pairs."""
    rot, t = np.eye(2), b.mean(0) - a.mean(0)
    for it in range(iterations + 1):
        ja = closest(a @ rot.T + t, b)
        jb = closest((b - t) @ rot, a)
        src, dst = np.vstack([a, a[jb]]), np.vstack([b[ja], b])
        d = np.linalg.norm(src @ rot.T + t - dst, axis=1)
        keep = d <= np.quantile(d, trim)
        if it == iterations:
            return rot, t, float(d[keep].mean())
        s, q = src[keep], dst[keep]
        cs, cq = s.mean(0), q.mean(0)
        u, _, vt = np.linalg.svd((s - cs).T @ (q - cq))
        rot = vt.T @ np.diag([1.0, np.sign(np.linalg.det(vt.T @ u.T))]) @ u.T
        t = cq - rot @ cs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("source")
    ap.add_argument("target")
    ap.add_argument("--lo", type=float, required=True)
    ap.add_argument("--hi", type=float, required=True)
    ap.add_argument("--out-source", required=True)
    ap.add_argument("--out-target", required=True)
    ap.add_argument("--sides", default="+1,-1")
    ap.add_argument("--every", type=int, default=4)
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--trim", type=float, default=0.9)
    ap.add_argument("--hop", type=int, default=1)
    a = ap.parse_args()
    if (not (0 <= a.lo < a.hi) or a.every < 1 or a.iterations < 1 or not (0 < a.trim <= 1)
            or a.hop < 1):
        sys.exit("segment_fit.py: need 0 <= --lo < --hi, --every >= 1, --iterations >= 1, "
                 "0 < --trim <= 1, --hop >= 1")
    try:
        s_pts, t_pts = read_points(a.source, 2), read_points(a.target, 2)
        sides = [float(v) for v in a.sides.split(",")]
    except (OSError, ValueError, IndexError) as e:
        sys.exit("segment_fit.py: %s" % e)
    for path, c in ((a.source, s_pts), (a.target, t_pts)):
        if c.ndim != 2 or len(c) < 3 or c.shape[1] != 2:
            sys.exit("segment_fit.py: %s: not a closed polyline of at least 3 points" % path)
    out_s, out_t = [], []
    for side in sides:
        if side not in (1.0, -1.0):
            sys.exit("segment_fit.py: --sides takes +1 and -1")
        masks = []
        for c in (s_pts, t_pts):
            on = np.where(c[:, 0] * side > 0)[0]
            if len(on) == 0:
                sys.exit("segment_fit.py: no vertex with x of sign %+d" % side)
            g = arc_length_from(c, on[c[on, 1].argmin()], a.hop)
            masks.append((g >= a.lo) & (g < a.hi) & (c[:, 0] * side > 0))
        ms, mt = masks
        if ms.sum() < 3 or mt.sum() < 3:
            sys.exit("segment_fit.py: side %+d: the segment has %d and %d vertices (need 3)"
                     % (side, ms.sum(), mt.sum()))
        rot, t, r = fit_rigid(s_pts[ms], t_pts[mt], a.iterations, a.trim)
        print("side %+d: %d and %d vertices, angle %.2f degrees, mean distance %.3g"
              % (side, ms.sum(), mt.sum(), np.degrees(np.arctan2(rot[1, 0], rot[0, 0])), r))
        for i in np.where(ms)[0][::a.every]:
            out_s.append(s_pts[i])
            out_t.append(rot @ s_pts[i] + t)
    for path, pts in ((a.out_source, out_s), (a.out_target, out_t)):
        with open(path, "w") as f:
            f.write("x,y\n")
            for p in pts:
                f.write("%.7f,%.7f\n" % tuple(p))
    print("segment_fit.py: %d pairs" % len(out_s))


if __name__ == "__main__":
    main()
