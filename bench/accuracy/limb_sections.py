#!/usr/bin/env python3
"""How a map bends the creature's arms, against the known map g (issue: correspondence).

    limb_sections.py --pair PAIRDIR PHI [PHI ...]

PAIRDIR is a 3D creature pair of make_pairs.py (source.obj, truth.xyz, target_resampled.obj:
a body and five arms radiating in the xy-plane); each PHI is the source's vertices mapped by a
method, in the source's vertex order and world units (vdb_match's deformed.obj, BCPD's y.txt,
a peer's xyz). Prints, per PHI, in 10^-3 of vdb_match's unit box:

  - the mean error |phi(v) - g(v)| on the body and on each arm, split into its components
    along the arm (radial), across it in the plane, and along z;
  - "stretch": the mean ratio |phi(a) - phi(b)| / |a - b| over the edges of the source's mesh
    that lie on an arm and point along it (within 25 deg), per arm, and the same for g itself:
    how much each map lengthens the arms' skin;
  - "sections": how much of the error is an along-arm displacement that varies linearly across
    the arm. In thin slices of each arm (5% of the arm's reach), the along-arm error is fitted
    as a + b * offset, offset the vertex's position across the arm (in-plane, then along z)
    from the slice's mean; the slope b (per unit offset, averaged over the arms) is what a
    rotation of the arm's cross-sections relative to g's would give (a bent elastic beam
    rotates its sections with the bend; a shear flow does not). The mean error is printed
    with that linear part removed (in-plane, z, both), and, as a control, with the same fit
    against a random regressor instead of the offset, which should remove nothing.

The arms are found by clustering the angles of the source's vertices farther than 0.6 of the
largest distance from the z-axis through the source's centroid; the body is what lies within
0.35 of it.
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points  # noqa: E402  (bench/accuracy/score.py)
from sdf_images import read_obj  # noqa: E402  (bench/accuracy/sdf_images.py)

ARMS = 5
BODY = 0.35  # of the largest distance from the axis
REACH = 0.6  # vertices beyond this fraction of it find the arms' directions
SLICE = 0.05  # slice thickness, fraction of the largest distance


def arms(v):
    """Arm label of every vertex (-1: body), the arms' unit directions, the centroid, rho, R."""
    c = v.mean(axis=0)
    r = v - c
    rho = np.hypot(r[:, 0], r[:, 1])
    ang = np.arctan2(r[:, 1], r[:, 0])
    big = rho.max()
    far = ang[rho > REACH * big]
    cent = np.linspace(-np.pi, np.pi, ARMS + 1)[:-1]
    for _ in range(50):  # k-means on the circle
        lab = np.argmin(np.abs(np.angle(np.exp(1j * (far[:, None] - cent[None, :])))), axis=1)
        cent = np.array([np.angle(np.exp(1j * far[lab == k]).mean()) if np.any(lab == k) else cent[k]
                         for k in range(ARMS)])
    lab = np.argmin(np.abs(np.angle(np.exp(1j * (ang[:, None] - cent[None, :])))), axis=1)
    lab[rho < BODY * big] = -1
    dirs = np.stack([np.cos(cent), np.sin(cent), np.zeros(ARMS)], axis=1)
    return lab, dirs, c, rho, big


def remove_linear(v, e, lab, dirs, rho, big, regressors):
    """e with, per arm slice, the part of the along-arm error linear in each regressor removed
    (one joint least-squares fit per slice); also the mean slope per regressor."""
    out = e.copy()
    slopes = []
    for k in range(ARMS):
        u = dirs[k]
        for a0 in np.arange(BODY, 1.0, SLICE):
            m = (lab == k) & (rho >= a0 * big) & (rho < (a0 + SLICE) * big)
            if m.sum() < 20:
                continue
            x = np.stack([f(v[m], k) for f in regressors], axis=1)
            x = x - x.mean(axis=0)
            along = e[m] @ u
            b, *_ = np.linalg.lstsq(np.c_[np.ones(len(x)), x], along, rcond=None)
            out[m] -= (x @ b[1:])[:, None] * u[None, :]
            slopes.append(b[1:])
    return out, np.mean(slopes, axis=0)


def arm_edges(v, tris, lab, dirs):
    """Per arm, the source's mesh edges (a, b) on it that point along it within 25 degrees."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    d = v[e[:, 1]] - v[e[:, 0]]
    d /= np.linalg.norm(d, axis=1)[:, None]
    out = []
    for k in range(ARMS):
        m = (lab[e[:, 0]] == k) & (lab[e[:, 1]] == k) & (np.abs(d @ dirs[k]) > np.cos(np.radians(25)))
        out.append(e[m])
    return out


def stretch(p, v, edges):
    return [np.mean(np.linalg.norm(p[e[:, 1]] - p[e[:, 0]], axis=1)
                    / np.linalg.norm(v[e[:, 1]] - v[e[:, 0]], axis=1)) for e in edges]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", required=True)
    ap.add_argument("phi", nargs="+")
    args = ap.parse_args()
    pair = json.load(open(os.path.join(args.pair, "pair.json")))
    if pair.get("dimension") != 3 or pair.get("shape") not in (None, "creature"):
        sys.exit("limb_sections.py: a 3D creature pair is needed")
    v = read_points(os.path.join(args.pair, "source.obj"), 3)
    g = read_points(os.path.join(args.pair, "truth.xyz"), 3)
    tgt = read_points(os.path.join(args.pair, "target_resampled.obj"), 3)
    both = np.vstack([v, tgt])
    scale = 0.6 / (both.max(axis=0) - both.min(axis=0)).max()  # vdb_match's placement
    lab, dirs, c, rho, big = arms(v)
    mesh_v, tris = read_obj(os.path.join(args.pair, "source.obj"))
    if len(mesh_v) != len(v):
        sys.exit("limb_sections.py: source.obj's vertices and faces do not agree")
    edges = arm_edges(v, tris, lab, dirs)
    print("g: stretch along the arms " + " ".join(f"{s:.4f}" for s in stretch(g, v, edges)))
    up = np.array([0.0, 0.0, 1.0])
    across = np.cross(up, dirs)
    in_plane = lambda p, k: p @ across[k]  # noqa: E731
    vertical = lambda p, k: p[:, 2]  # noqa: E731
    rng = np.random.default_rng(0)
    noise = lambda p, k: rng.standard_normal(len(p))  # noqa: E731
    mean = lambda e: np.linalg.norm(e, axis=1).mean() * scale * 1e3  # noqa: E731
    for path in args.phi:
        phi = read_points(path, 3)
        if len(phi) != len(v):
            sys.exit(f"limb_sections.py: {path} has {len(phi)} points for {len(v)} source vertices")
        e = phi - g
        print(f"{path}: err mean {mean(e):.3f} (x1e-3 of the box)")
        print(f"  body ({np.count_nonzero(lab < 0)} vertices) {mean(e[lab < 0]):.2f}")
        for k in range(ARMS):
            m = lab == k
            comp = [np.abs(e[m] @ d).mean() * scale * 1e3 for d in (dirs[k], across[k], up)]
            print(f"  arm {k} at {np.degrees(np.arctan2(dirs[k, 1], dirs[k, 0])):6.1f} deg "
                  f"({m.sum()} vertices) {mean(e[m]):.2f}: along {comp[0]:.2f} across {comp[1]:.2f} "
                  f"z {comp[2]:.2f}, mean along {(e[m] @ dirs[k]).mean() * scale * 1e3:+.2f}")
        print("  stretch along the arms " + " ".join(f"{s:.4f}" for s in stretch(phi, v, edges)))
        for name, regs in (("in-plane", [in_plane]), ("z", [vertical]),
                           ("in-plane and z", [in_plane, vertical]), ("control: random", [noise])):
            rest, slope = remove_linear(v, e, lab, dirs, rho, big, regs)
            print(f"  sections, {name}: slope {' '.join(f'{s:+.3f}' for s in slope)}, "
                  f"err mean without the linear part {mean(rest):.3f}")


if __name__ == "__main__":
    main()
