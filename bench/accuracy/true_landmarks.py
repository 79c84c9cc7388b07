#!/usr/bin/env python3
"""True landmark pairs of a benchmark pair: source vertices and their images under g.

Writes two CSV tables for `vdb_match match --landmarks A.csv B.csv`: every EVERY-th source
vertex that a selection keeps, and its image under the pair's ground-truth map g (truth.xyz).
A measurement tool, not a default: it asks how far a run gets when the correspondence is told
where the energy cannot see it (docs/results.md, "True correspondences on the two 2D motions
left").

Usage: true_landmarks.py PAIR_DIR --out-source A.csv --out-target B.csv
           [--moving F] [--box XMIN,XMAX,YMIN,YMAX[,ZMIN,ZMAX]] [--every N]
  --moving F  keep the vertices that g moves by more than F times its largest motion
              (default 0: every vertex, still ones too)
  --box       keep the vertices inside this box (world units of the pair)
  --every N   keep every N-th of the selected vertices, in file order (default 8)
Prints how many pairs it wrote. Exit status 0, or 1 with a message.
"""
import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points  # noqa: E402  (the benchmark's one reader of vertex files)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pair")
    ap.add_argument("--out-source", required=True)
    ap.add_argument("--out-target", required=True)
    ap.add_argument("--moving", type=float, default=0.0)
    ap.add_argument("--box", default=None)
    ap.add_argument("--every", type=int, default=8)
    a = ap.parse_args()
    try:
        meta = json.load(open(os.path.join(a.pair, "pair.json")))
        dim = int(meta["dimension"])
        ext = "obj" if dim == 3 else "polyline"
        src = read_points(os.path.join(a.pair, "source." + ext), dim)
        tru = np.loadtxt(os.path.join(a.pair, "truth.xyz"))[:, :dim]
    except (OSError, ValueError, KeyError) as e:
        sys.exit("true_landmarks.py: cannot read the pair %s: %s" % (a.pair, e))
    if src.shape != tru.shape:
        sys.exit("true_landmarks.py: %d source vertices against %d in truth.xyz" % (len(src), len(tru)))
    if a.every < 1:
        sys.exit("true_landmarks.py: --every must be >= 1")
    motion = np.linalg.norm(tru - src, axis=1)
    keep = motion > a.moving * motion.max() if a.moving > 0 else np.ones(len(src), bool)
    if a.box:
        b = [float(t) for t in a.box.split(",")]
        if len(b) != 2 * dim:
            sys.exit("true_landmarks.py: --box takes %d numbers in %dD" % (2 * dim, dim))
        for k in range(dim):
            keep &= (src[:, k] >= b[2 * k]) & (src[:, k] <= b[2 * k + 1])
    idx = np.where(keep)[0][::a.every]
    if len(idx) == 0:
        sys.exit("true_landmarks.py: the selection keeps no vertex")
    head = "x,y,z" if dim == 3 else "x,y"
    for path, pts in ((a.out_source, src), (a.out_target, tru)):
        with open(path, "w") as f:
            f.write(head + "\n")
            for i in idx:
                f.write(",".join("%.7f" % v for v in pts[i]) + "\n")
    print("true_landmarks.py: %d pairs" % len(idx))


if __name__ == "__main__":
    main()
