#!/usr/bin/env python3
"""How far a map turns a moving limb about its own axis, against the known map g (issue:
correspondence).

    limb_twist.py --pair PAIRDIR [--moving F] [--slabs N] PHI [PHI ...]

PAIRDIR is a 3D pair of make_pairs.py (source.obj, truth.xyz, pair.json) whose g swings one
limb (animal_leg_swing, creature_arm_up); each PHI is the source's vertices mapped by a method,
in the source's vertex order and world units (vdb_match's deformed.obj, or a directory holding
one). A round limb looks the same turned about its axis, so the surface terms hardly see such a
turn: this measures it.

- The limb is the source's vertices that g moves by more than F (default 0.3) times the largest
  motion: its outer part, which g turns about a joint nearer the body.
- Its axis in the pose of M2 is the principal direction of g(v) over those vertices, oriented
  away from the joint; the vertices are cut into N slabs (default 4) of equal count along it.
- In each slab, about the axis through the slab's centroid of g(v), the signed angle from
  g(v) to phi(v) (right-handed about the oriented axis, degrees), median and mean over the
  slab, and the slab's mean |phi(v) - g(v)| in 10^-3 of vdb_match's unit box (pair.json's
  source box, the placement of score.py is not needed: the unit box side is the source box's
  largest side times 1 + 2 margin, margin 0.2 by default).

A twist that grows along the limb is a torsion; a constant one a turn of the whole limb. A
sideways shift of the limb adds nothing to the mean angle over a slab (it averages out around
the axis), and PHI = g gives 0.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points  # noqa: E402  (bench/accuracy/score.py)


def fail(msg):
    print("limb_twist.py: " + msg, file=sys.stderr)
    sys.exit(2)


def limb_axis(moved):
    """Unit principal direction of the points `moved`, oriented from the end nearer the rest of
    the shape (the fewer-moving end is not known here: the caller orients it)."""
    c = moved.mean(axis=0)
    _, _, vt = np.linalg.svd(moved - c, full_matrices=False)
    return c, vt[0]


def signed_angles(a, b, axis):
    """Signed angle (degrees) from each row of a to the row of b, about the unit axis, after
    projecting both onto the plane normal to it."""
    a = a - np.outer(a @ axis, axis)
    b = b - np.outer(b @ axis, axis)
    return np.degrees(np.arctan2(np.cross(a, b) @ axis, (a * b).sum(axis=1)))


def twist_table(source, truth, phi, moving_fraction, slabs):
    """Rows (slab, vertices, median angle, mean angle, mean |phi - g|, world units) over the
    slabs of the moving limb, ordered from the joint outwards."""
    motion = np.linalg.norm(truth - source, axis=1)
    limb = motion > moving_fraction * motion.max()
    if limb.sum() < 4 * slabs:
        fail("only %d vertices move by more than %g of the largest motion: no limb to measure"
             % (limb.sum(), moving_fraction))
    g, p = truth[limb], phi[limb]
    centre, axis = limb_axis(g)
    along = (g - centre) @ axis
    # Orient the axis away from the joint: the limb's least-moving vertices lie at the joint.
    m = motion[limb]
    if np.corrcoef(along, m)[0, 1] < 0:
        axis, along = -axis, -along
    order = np.argsort(along)
    rows = []
    for k, idx in enumerate(np.array_split(order, slabs)):
        c = g[idx].mean(axis=0)
        ang = signed_angles(g[idx] - c, p[idx] - c, axis)
        err = np.linalg.norm(p[idx] - g[idx], axis=1).mean()
        rows.append((k, len(idx), float(np.median(ang)), float(ang.mean()), float(err)))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", required=True)
    ap.add_argument("--moving", type=float, default=0.3)
    ap.add_argument("--slabs", type=int, default=4)
    ap.add_argument("phi", nargs="+")
    a = ap.parse_args()
    if not 0 < a.moving < 1:
        fail("--moving must lie in (0, 1)")
    if a.slabs < 1:
        fail("--slabs must be at least 1")
    pair = json.load(open(os.path.join(a.pair, "pair.json")))
    if pair["dimension"] != 3:
        fail("%s is a 2D pair: a curve's limb cannot turn about its axis" % pair["name"])
    source = read_points(os.path.join(a.pair, "source.obj"), 3)
    truth = read_points(os.path.join(a.pair, "truth.xyz"), 3)
    for path in a.phi:
        f = os.path.join(path, "deformed.obj") if os.path.isdir(path) else path
        report = os.path.join(path, "report.json")
        unit = "box"
        scale = 1e3
        if os.path.isdir(path) and os.path.exists(report):
            scale *= json.load(open(report))["placement"]["scale"]
        else:
            unit = "world"
        phi = read_points(f, 3)
        if len(phi) != len(source) or len(truth) != len(source):
            fail("%s: %d points, the source has %d" % (f, len(phi), len(source)))
        print("%s (%s)" % (pair["name"], path))
        print("  slab  vertices  twist median  twist mean  |phi-g| (1e-3 %s)" % unit)
        for k, n, med, mean, err in twist_table(source, truth, phi, a.moving, a.slabs):
            print("  %4d  %8d  %11.1f°  %9.1f°  %8.2f" % (k, n, med, mean, err * scale))


if __name__ == "__main__":
    main()
