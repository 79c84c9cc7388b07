#!/usr/bin/env python3
"""Synthetic shape pairs with a known ground-truth map g, for the accuracy benchmark
(bench/bench_accuracy.sh; issue 8, item 3).

Every pair is a source shape M1 and the target M2 = g(M1): the source's vertices moved by g,
with the same connectivity, so g(v) is the true correspondence of every source vertex v. g is
a composition of flows (RK4, FLOW_STEPS steps over t in [0, 1]) of smooth velocity fields and
of exact similarity motions, hence a diffeomorphism; the script checks that the central-
difference Jacobian determinant of g is positive on every source vertex and on a grid around
the shape, that both meshes are closed, consistently and outwardly oriented and free of
self-intersections (3D: no edge crosses a triangle that does not contain it; 2D: no two
segments cross, counter-clockwise).

Shapes
- 3D "creature": the starfish-like creature of tools/make_example_assets.py (a round body and
  five tapered, flattened arms; smooth union of round cones), meshed at its zero level by
  OpenVDB's volumeToMesh on a dense grid of CREATURE_VOXEL (implicit_mesh: quads split along
  their shorter diagonal, vertices sorted, so the output does not depend on OpenVDB's order).
- 3D "animal": a quadruped (body, neck and head, four legs, a tail; round cones, animal_parts),
  meshed the same way at ANIMAL_VOXEL.
- 2D "figure": the person-like silhouette (pose A) of tools/make_example_assets.py, resampled
  uniformly in arc length to FIGURE_POINTS points, counter-clockwise.

Maps g (see PAIRS; pair.json "kind" says near-isometric, large motion or stretch)
- articulated: limbs rotating about a joint by a rotation whose rate is blended smoothly by a
  weight along the limb (logistic in the distance along the limb, times a lateral window, or in
  3D for the animal a cylinder about the limb: radial_limb_rotation); the weight moves with the
  rotation, so the limb beyond the ramp turns rigidly ("skeleton-driven smooth flow"). Creature:
  three arms by 22-32 deg; animal: the head turned 30 deg, the tail swung 40 deg, and the head
  turned 22 deg with the spine bent 16 deg sideways (every extremity moves: a whole-body pose
  change, as between two scans of an animal); figure: an arm raised 30 deg and a forearm
  turned 30 deg.
- large articulated motion, the same flows further: the creature's arm raised 100 deg, the
  animal's front leg swung 90 deg forward, the figure's arms raised 60 and 90 deg, its legs
  spread 25 deg, a frontal squat (thighs out 22 deg, shins back in 40 deg), a star jump (arms
  90 deg, legs 20 deg).
- twist and swirl: 3D creature: a twist of one arm about its own axis growing along the arm, a
  pinwheel swirl about the body's axis whose angle grows with the distance from it, and a
  cupping bend of the arms; animal: the torso twisted about its long axis (-11 to +11 deg);
  2D: both arms curled (rotation about the shoulder whose angle grows along the arm, in
  opposite senses), a swirl about the chest and a sideways bend of the body.
- stretch: the flow of a spatially varying anisotropic rate field (scale about 1.15 x 0.9 x 1.0,
  the rate modulated by +-25 %), then a small rigid rotation and translation.

Output: one directory per pair, holding
  source.obj, target.obj (3D) or source.polyline, target.polyline (2D);
  truth.xyz: per source vertex (file order) g(v), world units, space separated;
  target_resampled.obj / .polyline: the target sampled independently of the source's vertices
             (3D: re-meshed from its level set at the mean edge length; 2D: resampled by arc
             length with 7% fewer points, half a spacing off), for bench_accuracy.sh --resampled;
  target_scan.obj / .polyline: target_resampled with Gaussian noise of std 0.2% of the
             source's box diagonal on every vertex (a scanner's error; same faces), for
             bench_accuracy.sh --scan and compare_peers.sh --scan;
  landmarks_source.csv, landmarks_target.csv: 5 points of the source (farthest-point
             sampling from the vertex farthest from the centroid: the creature's arm tips; the
             animal's tail, head, two feet and a point of its flank; the figure's head, hands,
             right foot and a point of its crotch) and their images g(v), for
             vdb_match --landmarks (bench_accuracy.sh --landmarks);
  pair.json: name, dimension, shape, kind, description, vertex count, mean/max motion
             |g(v) - v| (world and as a fraction of the source's bounding-box diagonal),
             checks (min det Dg, edges).
Files are written with 7 decimals; g is applied to the rounded source coordinates, and the
target file holds the same numbers as truth.xyz.

Usage (system python, which has numpy and pyopenvdb):
    /usr/bin/python3 bench/accuracy/make_pairs.py OUTDIR [--only NAME[,NAME...]]
    /usr/bin/python3 bench/accuracy/make_pairs.py --list [all|speed]
--list prints the pair names, all of them or a named set (SETS: "speed", the eight pairs of
the speed issue's accuracy benchmark). Deterministic; the seventeen pairs take about 2 minutes
(2 loaded cores), the 3D ones most of it.
"""

import json
import math
import os
import sys
import time
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # no __pycache__ in tools/
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
import make_example_assets as mea  # noqa: E402  (shapes, round cones, polyline helpers)

FLOW_STEPS = 24             # RK4 steps per flow
DECIMALS = 7                # written coordinates
SCAN_NOISE = 0.002          # target_scan.*: noise std, fraction of the source box diagonal
CREATURE_VOXEL = 0.010      # meshing grid of the 3D creature (world units; ~1.9 across)
FIGURE_POINTS = 1500        # points of the 2D figure (perimeter ~8.5, ~1.9 tall)
JACOBIAN_STEP = 1e-4        # central differences
JACOBIAN_GRID = (24, 96)    # grid points per axis around the shape (3D, 2D)


# ---------------------------------------------------------------------------------------------
# flows
# ---------------------------------------------------------------------------------------------

def logistic(s):
    return 1.0 / (1.0 + np.exp(-s))


def rk4_flow(x, velocity, steps=FLOW_STEPS, t_end=1.0):
    """x(t_end) for dx/dt = velocity(x, t), x(0) = x (steps RK4 steps over [0, t_end])."""
    x = np.array(x, dtype=float)
    h = t_end / steps
    for i in range(steps):
        t = i * h
        k1 = velocity(x, t)
        k2 = velocity(x + 0.5 * h * k1, t + 0.5 * h)
        k3 = velocity(x + 0.5 * h * k2, t + 0.5 * h)
        k4 = velocity(x + h * k3, t + h)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def rot2(radians):
    c, s = math.cos(radians), math.sin(radians)
    return np.array([[c, -s], [s, c]])


def perp2(v):
    """Rotation by +90 degrees of the last axis (2D)."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def rotation_flow(pivot, degrees, weight, axis=None, t_end=1.0):
    """Flow of a rotation by `degrees` about `pivot` (3D: about `axis`; 2D: in the plane,
    positive = counter-clockwise) whose rate is weighted by w = weight(back), back = x - pivot
    rotated back by the angle reached at time t: where w = 1 the part turns rigidly. t_end < 1:
    the flow stopped at that time (the motion so far, for sequences: make_sequence.py)."""
    pivot = np.asarray(pivot, dtype=float)
    omega = math.radians(degrees)
    if len(pivot) == 2:
        def velocity(x, t):
            w = weight((x - pivot) @ rot2(-omega * t).T)
            return omega * w[:, None] * perp2(x - pivot)
    else:
        a = np.asarray(axis, dtype=float)
        a = a / np.linalg.norm(a)

        def velocity(x, t):
            w = weight((x - pivot) @ mea.rotation_matrix(a, -omega * t).T)
            return omega * w[:, None] * np.cross(a, x - pivot)

    return lambda x: rk4_flow(x, velocity, t_end=t_end)


def limb_rotation(pivot, direction, degrees, start, ramp, lateral, axis=None, plane_normal=None,
                  t_end=1.0):
    """rotation_flow of a limb, weighted by w = logistic((s - start)/ramp) * L(l), s the distance
    along `direction` from the pivot, l the lateral coordinate (2D: along perp(direction); 3D:
    along plane_normal x direction), L = `lateral`(l) a smooth window."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    lat_dir = perp2(d) if len(d) == 2 else np.cross(plane_normal, d)

    def weight(back):
        return logistic((back @ d - start) / ramp) * lateral(back @ lat_dir)

    return rotation_flow(pivot, degrees, weight, axis, t_end)


def window(half_width, power=4):
    return lambda l: np.exp(-(l / half_width) ** power)


def one_sided(edge, width, sign):
    """Smooth cut-off: about 1 on the side sign*(l - edge) > 0, 0 on the other."""
    return lambda l: logistic(sign * (l - edge) / width)


def similarity(rotation, translation, centre):
    rotation = np.asarray(rotation, dtype=float)
    translation = np.asarray(translation, dtype=float)
    centre = np.asarray(centre, dtype=float)
    return lambda x: (x - centre) @ rotation.T + centre + translation


def compose(*maps):
    def g(x):
        for m in maps:
            x = m(x)
        return x
    return g


def min_jacobian(g, points):
    dim = points.shape[1]
    cols = []
    for k in range(dim):
        e = np.zeros(dim)
        e[k] = JACOBIAN_STEP
        cols.append((g(points + e) - g(points - e)) / (2.0 * JACOBIAN_STEP))
    return float(np.linalg.det(np.stack(cols, axis=-1)).min())


# ---------------------------------------------------------------------------------------------
# 3D creature
# ---------------------------------------------------------------------------------------------

UP = np.array([0.0, 0.0, 1.0])


def arm(i):
    return mea.arm_directions()[i]


def implicit_mesh(function, lo, hi, voxel, name):
    """Closed triangle mesh of the zero level of `function` (negative inside) over the box
    [lo, hi]: OpenVDB's volumeToMesh on a dense grid of `voxel`, quads split along their shorter
    diagonal, vertices sorted lexicographically, faces sorted (so that the output does not
    depend on OpenVDB's vertex order)."""
    import pyopenvdb as vdb
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    n = np.ceil((hi - lo) / voxel).astype(int) + 1
    axes = [lo[a] + voxel * np.arange(n[a]) for a in range(3)]
    grid_points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    values = np.concatenate([function(c) for c in np.array_split(grid_points, 64)]).reshape(n)
    if values[0, :, :].min() <= 0 or values[-1].min() <= 0 or values[:, 0].min() <= 0 or \
            values[:, -1].min() <= 0 or values[:, :, 0].min() <= 0 or values[:, :, -1].min() <= 0:
        raise RuntimeError("%s: meshing grid too small" % name)
    grid = vdb.FloatGrid(background=3.0 * voxel)
    grid.copyFromArray(values.astype(np.float32), ijk=(0, 0, 0), tolerance=0.0)
    grid.transform = vdb.createLinearTransform(voxelSize=voxel)
    points, triangles, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
    points = points.astype(float) + lo
    q = quads.astype(np.int64)
    diag02 = np.linalg.norm(points[q[:, 0]] - points[q[:, 2]], axis=1)
    diag13 = np.linalg.norm(points[q[:, 1]] - points[q[:, 3]], axis=1)
    split02 = (diag02 <= diag13)[:, None]
    t1 = np.where(split02, q[:, [0, 1, 2]], q[:, [0, 1, 3]])
    t2 = np.where(split02, q[:, [0, 2, 3]], q[:, [1, 2, 3]])
    tris = np.vstack([triangles.astype(np.int64).reshape(-1, 3), t1, t2])
    # round as written, sort vertices, drop unreferenced ones
    points = np.round(points, DECIMALS)
    used = np.unique(tris)
    order = used[np.lexsort((points[used, 2], points[used, 1], points[used, 0]))]
    new_index = np.full(len(points), -1, dtype=np.int64)
    new_index[order] = np.arange(len(order))
    points = points[order]
    tris = new_index[tris]
    # rotate each triangle so that its smallest index comes first, then sort the faces
    first = np.argmin(tris, axis=1)
    tris = np.stack([tris[np.arange(len(tris)), (first + k) % 3] for k in range(3)], axis=1)
    tris = tris[np.lexsort((tris[:, 2], tris[:, 1], tris[:, 0]))]
    if len(np.unique(points, axis=0)) != len(points):
        raise RuntimeError("%s: duplicate vertices" % name)
    if signed_volume(points, tris) < 0.0:
        tris = tris[:, [0, 2, 1]]
    return points, tris


def creature_mesh():
    """The creature (make_example_assets.starfish_function) meshed by implicit_mesh."""
    return implicit_mesh(mea.starfish_function, (-1.15, -1.05, -0.4), (1.15, 1.15, 0.4),
                         CREATURE_VOXEL, "creature")


def signed_volume(points, tris):
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def edges_of(tris):
    return np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])


def check_closed_oriented(points, tris, name):
    """Every directed edge once, its reverse once (closed, manifold edges, consistently
    oriented); outward (positive volume); no degenerate triangle."""
    e = edges_of(tris)
    key = e[:, 0] * len(points) + e[:, 1]
    if len(np.unique(key)) != len(key):
        raise RuntimeError("%s: a directed edge is used twice (orientation or non-manifold)" % name)
    rev = np.sort(key)
    if not np.all(np.isin(e[:, 1] * len(points) + e[:, 0], rev, assume_unique=False)):
        raise RuntimeError("%s: open mesh (an edge without its opposite)" % name)
    if signed_volume(points, tris) <= 0.0:
        raise RuntimeError("%s: not outward oriented" % name)
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if area.min() <= 1e-12:
        raise RuntimeError("%s: degenerate triangle" % name)


def self_intersections(points, tris):
    """Number of (edge, triangle) pairs, edge not a side nor touching a corner of the triangle,
    where the edge crosses the triangle (strictly). Two triangles of a mesh intersect only if an
    edge of one crosses the other (or they share a vertex), so 0 means no self-intersection."""
    e = np.unique(np.sort(edges_of(tris), axis=1), axis=0)
    cell = np.linalg.norm(points[e[:, 0]] - points[e[:, 1]], axis=1).max() * 1.01
    lo = points.min(axis=0)

    def cells(lo_c, hi_c):
        """(item, cell key) for every cell a box [lo_c, hi_c] (at most 2 cells wide) touches."""
        items, keys = [], []
        dims = np.floor((points.max(axis=0) - lo) / cell).astype(np.int64) + 3
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    c = lo_c + np.array([dx, dy, dz])
                    ok = np.all(c <= hi_c, axis=1)
                    idx = np.nonzero(ok)[0]
                    items.append(idx)
                    keys.append((c[idx, 0] * dims[1] + c[idx, 1]) * dims[2] + c[idx, 2])
        return np.concatenate(items), np.concatenate(keys)

    tp = points[tris]
    t_items, t_keys = cells(np.floor((tp.min(axis=1) - lo) / cell).astype(np.int64),
                            np.floor((tp.max(axis=1) - lo) / cell).astype(np.int64))
    ep = points[e]
    e_items, e_keys = cells(np.floor((ep.min(axis=1) - lo) / cell).astype(np.int64),
                            np.floor((ep.max(axis=1) - lo) / cell).astype(np.int64))
    order = np.argsort(t_keys, kind="stable")
    t_items, t_keys = t_items[order], t_keys[order]
    begin = np.searchsorted(t_keys, e_keys, side="left")
    end = np.searchsorted(t_keys, e_keys, side="right")
    count = end - begin
    pair_edge = np.repeat(e_items, count)
    offsets = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    pair_tri = t_items[np.repeat(begin, count) + offsets]
    pairs = np.unique(pair_edge * len(tris) + pair_tri)
    pe, pt = pairs // len(tris), pairs % len(tris)
    ev, tv = e[pe], tris[pt]
    incident = np.any((ev[:, :1] == tv) | (ev[:, 1:] == tv), axis=1)
    pe, pt = pe[~incident], pt[~incident]
    crossings = 0
    for chunk in np.array_split(np.arange(len(pe)), max(1, len(pe) // 500000)):
        p0, p1 = points[e[pe[chunk], 0]], points[e[pe[chunk], 1]]
        a, b, c = (points[tris[pt[chunk], k]] for k in range(3))

        def orient(p, q, r, s):
            return np.einsum("ij,ij->i", q - p, np.cross(r - p, s - p))

        s0, s1 = orient(a, b, c, p0), orient(a, b, c, p1)
        u, v, w = orient(p0, p1, a, b), orient(p0, p1, b, c), orient(p0, p1, c, a)
        hit = (s0 * s1 < 0.0) & (((u > 0) & (v > 0) & (w > 0)) | ((u < 0) & (v < 0) & (w < 0)))
        crossings += int(np.count_nonzero(hit))
    return crossings, len(pe)


def creature_articulated():
    maps = []
    # (arm, axis kind, degrees): "up"/"down" about the horizontal axis across the arm, "swing"
    # about the vertical axis (in the plane); pivot 0.33 from the centre, ramp at 0.45.
    for i, kind, degrees in ((0, "up", 32.0), (2, "down", 25.0), (3, "swing", 22.0)):
        d = arm(i)
        axis = UP if kind == "swing" else np.cross(d, UP) * (1.0 if kind == "up" else -1.0)
        maps.append(limb_rotation(0.33 * d, d, degrees, start=0.45 - 0.33, ramp=0.05,
                                  lateral=window(0.26), axis=axis, plane_normal=UP))
    return compose(*maps)


def creature_arm_up():
    # Large articulated motion in 3D (issue: correspondence): arm 0 raised 100 degrees out of the
    # plane (past the vertical) about the horizontal axis across it, pivot 0.33 from the centre
    # as in creature_articulated. At 70 degrees vdb_match still finds the arm (err mean 5.2e-3
    # of the box at 4..7, like the other creature pairs); at 100 it does not.
    d = arm(0)
    return limb_rotation(0.33 * d, d, 100.0, start=0.45 - 0.33, ramp=0.05, lateral=window(0.26),
                         axis=np.cross(d, UP), plane_normal=UP)


def creature_swirl():
    d1 = arm(1)
    twist_deg, swirl_deg, cup = 50.0, 16.0, 0.14

    def twist(x, t):  # about arm 1's axis (through the centre), angle growing along the arm
        s = x @ d1
        lat = x @ np.cross(UP, d1)
        w = math.radians(twist_deg) * logistic((s - 0.55) / 0.1) * np.exp(-(lat / 0.3) ** 4)
        return w[:, None] * np.cross(d1, x)

    def swirl(x, t):  # about the z axis, angle growing with the distance rho from it
        rho = np.hypot(x[:, 0], x[:, 1])
        w = math.radians(swirl_deg) * rho ** 2
        return w[:, None] * np.cross(UP, x)

    def bend(x, t):  # cupping: z rises with rho^2 (arms curl up)
        rho2 = x[:, 0] ** 2 + x[:, 1] ** 2
        v = np.zeros_like(x)
        v[:, 2] = cup * rho2
        return v

    return compose(lambda x: rk4_flow(x, twist), lambda x: rk4_flow(x, swirl),
                   lambda x: rk4_flow(x, bend))


def stretch_rates(x, rates):
    """Anisotropic rate field: rates * (x - 0), modulated smoothly by +-25 %."""
    m = 1.0 + 0.25 * np.sin(1.7 * x[:, 0] + 0.4) * np.cos(1.3 * x[:, 1] - 0.3)
    return (x * rates) * m[:, None]


def creature_stretch():
    rates = np.log(np.array([1.15, 0.9, 1.0]))
    rotation = (mea.rotation_matrix((1.0, 2.0, 3.0), math.radians(6.0)))
    return compose(lambda x: rk4_flow(x, lambda y, t: stretch_rates(y, rates)),
                   similarity(rotation, (0.06, -0.04, 0.03), (0.0, 0.0, 0.0)))


# ---------------------------------------------------------------------------------------------
# 3D animal (issue: correspondence): a quadruped with a head on a neck, four legs and a tail
# ---------------------------------------------------------------------------------------------

ANIMAL_VOXEL = 0.012   # meshing grid (world units; the animal is ~2.2 long)
ANIMAL_BLEND = 0.03    # smooth-union width (log-sum-exp)
ANIMAL_SHOULDER = np.array([0.36, -0.15, -0.10])   # top of the front right leg
ANIMAL_NECK = np.array([0.50, 0.0, 0.10])          # base of the neck
ANIMAL_TAIL = np.array([-0.62, 0.0, 0.08])         # root of the tail


def animal_parts():
    """Round cones (a, r_a, b, r_b) of the animal: body along x, neck and head at +x, four legs
    (left y > 0, right y < 0), tail at -x."""
    parts = [((-0.55, 0.0, 0.0), 0.25, (0.45, 0.0, 0.02), 0.27),     # body
             ((0.50, 0.0, 0.10), 0.15, (0.72, 0.0, 0.42), 0.11),     # neck
             ((0.72, 0.0, 0.50), 0.15, (0.98, 0.0, 0.40), 0.07),     # head, snout forward
             ((-0.62, 0.0, 0.08), 0.075, (-1.10, 0.0, 0.32), 0.035)]  # tail
    for x in (0.36, -0.44):
        for y in (0.15, -0.15):
            parts.append(((x, y, -0.10), 0.11, (x + 0.02, 1.07 * y, -0.78), 0.065))  # legs
    return [(np.array(a), ra, np.array(b), rb) for a, ra, b, rb in parts]


def animal_function(p):
    """Implicit function of the animal (negative inside; a distance only approximately)."""
    return mea.smooth_union([mea.sd_round_cone(p, a, b, ra, rb)
                             for a, ra, b, rb in animal_parts()], ANIMAL_BLEND)


def animal_mesh():
    return implicit_mesh(animal_function, (-1.2, -0.35, -0.92), (1.12, 0.35, 0.72),
                         ANIMAL_VOXEL, "animal")


def radial_limb_rotation(pivot, direction, degrees, start, ramp, radius, axis, power=4,
                         t_end=1.0):
    """rotation_flow of a 3D limb about `axis` through `pivot`, weighted by
    w = logistic((s - start)/ramp) * exp(-(r/radius)^power), s the distance along `direction` from
    the pivot and r the distance from that line: a cylinder about the limb, so that other limbs
    beside it (any side) stay still."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)

    def weight(back):
        s = back @ d
        r = np.linalg.norm(back - s[:, None] * d, axis=1)
        return logistic((s - start) / ramp) * np.exp(-(r / radius) ** power)

    return rotation_flow(pivot, degrees, weight, axis, t_end)


def animal_head_turn():
    # the head on its neck turns 30 deg sideways (about the vertical through the neck base)
    return radial_limb_rotation(ANIMAL_NECK, (0.22, 0.0, 0.32), 30.0, start=0.10, ramp=0.04,
                                radius=0.45, axis=UP)


def animal_tail_swing():
    # the tail swings 40 deg sideways about the vertical through its root
    return radial_limb_rotation(ANIMAL_TAIL, (-0.48, 0.0, 0.24), 40.0, start=0.06, ramp=0.03,
                                radius=0.2, axis=UP)


def animal_torso_twist():
    # the torso twists about its long axis: the angle grows smoothly from -11 deg behind to
    # +11 deg in front (22 deg between the hips and the shoulders); legs, neck and tail follow
    # the part of the body they hang from
    twist = math.radians(22.0)
    x_axis = np.array([1.0, 0.0, 0.0])

    def velocity(x, t):
        w = twist * (logistic(x[:, 0] / 0.25) - 0.5)
        return w[:, None] * np.cross(x_axis, x)

    return lambda x: rk4_flow(x, velocity)


def animal_body_bend():
    # A whole-body pose change, as a scanned animal's between two sessions: the head turns 22 deg
    # sideways on its neck (as animal_head_turn), then the spine bends 16 deg sideways about the
    # vertical, the angle growing smoothly from -8 deg behind to +8 deg in front; legs, neck,
    # head and tail follow the part of the body they hang from. Every extremity moves.
    head = radial_limb_rotation(ANIMAL_NECK, (0.22, 0.0, 0.32), 22.0, start=0.10, ramp=0.04,
                                radius=0.45, axis=UP)
    bend = math.radians(16.0)

    def velocity(x, t):
        w = bend * (logistic(x[:, 0] / 0.25) - 0.5)
        return w[:, None] * np.cross(UP, x)

    return compose(head, lambda x: rk4_flow(x, velocity))


def animal_leg_swing():
    # Large articulated motion: the front right leg swung 90 deg forward at the shoulder, from
    # standing to horizontal (about -y through the shoulder). The weight is flat across the leg
    # (radius 0.2, power 8: > 99% on its surface, 0.11 from its axis; nil at the other legs) and
    # starts below the belly (s > 0.2), so that the whole leg turns and does not lag into a fan.
    return radial_limb_rotation(ANIMAL_SHOULDER, (0.02, -0.01, -0.68), 90.0, start=0.2,
                                ramp=0.03, radius=0.2, axis=(0.0, -1.0, 0.0), power=8)


# ---------------------------------------------------------------------------------------------
# 2D figure
# ---------------------------------------------------------------------------------------------

def figure_polyline():
    h = mea.FIGURE_CONTOUR_SPACING
    x = np.arange(-0.8, 0.8, h) + 0.3 * h
    y = np.arange(-1.1, 1.2, h) + 0.3 * h
    gx, gy = np.meshgrid(x, y)
    values = mea.figure_function(np.stack([gx, gy], axis=-1), "a")
    contours = mea.zero_contours(values, x, y)
    if len(contours) != 1:
        raise RuntimeError("figure: %d contours, expected one" % len(contours))
    poly = np.round(mea.resample_closed(contours[0], FIGURE_POINTS), DECIMALS)
    if mea.signed_area(poly) < 0.0:
        poly = poly[::-1]
    # start at the lowest-then-leftmost point (a canonical, deterministic start)
    start = np.lexsort((poly[:, 0], poly[:, 1]))[0]
    return np.roll(poly, -start, axis=0)


# Limbs of pose A (make_example_assets.FIGURE_LIMBS["a"], right side x > 0): shoulder
# (0.15, 0.44), elbow (0.33, 0.22), hand (0.47, -0.07).
SHOULDER = np.array([0.15, 0.44])
ELBOW = np.array([0.33, 0.22])
HAND = np.array([0.46, -0.05])


def mirror(p):
    return np.array([-p[0], p[1]])


def figure_articulated():
    # right arm raised 30 degrees at the shoulder (counter-clockwise, away from the torso): the
    # torso lies on the arm's clockwise side (lateral < 0), cut off between the arm's inner
    # surface (l ~ -0.07) and the torso (l < -0.12); left forearm turned out 30 degrees at the
    # elbow (clockwise), the torso on its counter-clockwise side (l > 0.12).
    # (Swinging a leg out by 15-22 degrees instead, or raising both arms, made the forward match
    # of November 2026 (levels 4..9) miss the foot or the hand: a local minimum, not a benchmark.)
    raise_arm = limb_rotation(SHOULDER, HAND - SHOULDER, 30.0, start=0.07, ramp=0.03,
                              lateral=lambda l: one_sided(-0.10, 0.01, +1)(l)
                              * window(0.3)(l))
    elbow = mirror(ELBOW)
    turn_forearm = limb_rotation(elbow, mirror(HAND) - elbow, -30.0, start=0.03, ramp=0.025,
                                 lateral=lambda l: one_sided(0.10, 0.015, -1)(l)
                                 * window(0.3)(l))
    return compose(raise_arm, turn_forearm)


def figure_arms_up():
    # Large articulated motion (issue: correspondence): both arms raised 60 degrees at the
    # shoulders, from hanging at the sides to about horizontal, with the soft one-sided weights
    # of figure_articulated (raise_arms: the arms' inner sides lag into a flap; the hands end
    # bent down).
    return raise_arms(60.0)


# Legs of pose A, right side: hip (0.08, 0.03), knee (0.13, -0.44), ankle (0.15, -0.90).
HIP = np.array([0.08, 0.03])
KNEE = np.array([0.13, -0.44])
ANKLE = np.array([0.15, -0.90])


def raise_arms(degrees, cut=0.10, width=0.01):
    """Both arms raised by `degrees` at the shoulders (outwards, mirror-symmetric). The torso side
    of each arm stays: the weight is cut off at lateral distance `cut` from the arm's axis,
    over `width` (the arm's inner surface is at about 0.07). figure_arms_up keeps the soft cut of
    figure_articulated (width 0.01: the arm's inner surface turns at ~95% of the rate, lags, and
    the skin between arm and torso is drawn into a flap); the sharp cut (0.004) turns the whole
    arm (> 99%) and shears the gap between arm and torso instead."""
    right = limb_rotation(SHOULDER, HAND - SHOULDER, degrees, start=0.07, ramp=0.03,
                          lateral=lambda l: one_sided(-cut, width, +1)(l) * window(0.3)(l))
    left = limb_rotation(mirror(SHOULDER), mirror(HAND) - mirror(SHOULDER), -degrees, start=0.07,
                         ramp=0.03,
                         lateral=lambda l: one_sided(cut, width, -1)(l) * window(0.3)(l))
    return compose(right, left)


SHARP_CUT = 0.004  # width of the one-sided weights of the large-motion figure pairs


def spread_legs(hip_degrees, knee_degrees=0.0):
    """Both legs swung out by `hip_degrees` at the hips (mirror-symmetric), then, if
    `knee_degrees`, both shins turned back in by it at the (moved) knees. Each leg turns whole:
    the swing's weight is cut off sharply (SHARP_CUT) at the body's mid-line x = 0, the middle of
    the gap between the legs at every height. (Until 2026-11-27 the cut lay at a lateral distance
    0.105 from the hip-knee axis: in the gap at the thigh, but through the inner edge of the foot,
    which then stayed while the rest of the leg swung, stretching 0.045 of the outline ~10x.)"""
    maps = []
    for side in (+1, -1):
        flip = (lambda p: p) if side > 0 else mirror
        hip, knee, ankle = flip(HIP), flip(KNEE), flip(ANKLE)
        swing = leg_swing(hip, knee, side * hip_degrees, side)
        maps.append(swing)
        if knee_degrees:
            k, a = swing(knee[None, :])[0], swing(ankle[None, :])[0]
            maps.append(limb_rotation(
                k, a - k, -side * knee_degrees, start=0.02, ramp=0.025,
                lateral=lambda l, s=side: one_sided(-s * 0.11, SHARP_CUT, s)(l) * window(0.25)(l)))
    return compose(*maps)


def leg_swing(hip, knee, degrees, side):
    """rotation_flow of the leg on side `side` (+1: x > 0) about `hip`: weight
    logistic((s - 0.10)/0.03) along the hip-knee axis, times a sharp cut at the mid-line x = 0
    of the rest frame, times a lateral window on the outer side (half-width 0.22)."""
    d = (knee - hip) / np.linalg.norm(knee - hip)
    lat_dir = perp2(d)

    def weight(back):
        mid = one_sided(0.0, SHARP_CUT, side)(back[:, 0] + hip[0])
        return logistic((back @ d - 0.10) / 0.03) * mid * window(0.22)(back @ lat_dir)

    return rotation_flow(hip, degrees, weight)


def figure_arms_horizontal():
    # Large articulated motion: both arms raised 90 deg, from hanging to horizontal
    return raise_arms(90.0, width=SHARP_CUT)


def figure_legs_spread():
    # Large articulated motion: both legs swung out 25 deg at the hips
    return spread_legs(25.0)


def figure_knees_bent():
    # Large articulated motion: thighs out 22 deg at the hips, shins back in 40 deg at the
    # knees (a frontal squat, knees apart)
    return spread_legs(22.0, 40.0)


def figure_star():
    # Large articulated motion (a star jump): arms raised 90 deg and legs spread 20 deg
    return compose(raise_arms(90.0, width=SHARP_CUT), spread_legs(20.0))


def figure_swirl():
    arm_r = HAND - SHOULDER
    arm_l = mirror(HAND) - mirror(SHOULDER)

    def curl(pivot, direction, degrees, inner_sign):
        """Rotation about the shoulder whose angle grows along the arm: the arm bends into an
        arc (a curl); the torso side (inner_sign) is cut off."""
        d = direction / np.linalg.norm(direction)
        omega = math.radians(degrees)
        lat_dir = perp2(d)

        def velocity(x, t):
            r = x - pivot
            s = r @ d
            lat = r @ lat_dir
            w = omega * logistic((s - 0.3) / 0.12)
            w = w * logistic((inner_sign * lat + 0.095) / 0.02) * np.exp(-(lat / 0.25) ** 4)
            return w[:, None] * perp2(r)

        return lambda x: rk4_flow(x, velocity)

    centre = np.array([0.0, 0.25])

    def swirl(x, t):
        r = x - centre
        rho = np.linalg.norm(r, axis=1)
        w = math.radians(10.0) * logistic((rho - 0.55) / 0.1)
        return w[:, None] * perp2(r)

    def bend(x, t):  # sideways bend of the body: x rises with y^2
        v = np.zeros_like(x)
        v[:, 0] = 0.10 * (x[:, 1] - 0.1) ** 2
        return v

    # right arm curls up (counter-clockwise, torso on its clockwise side: inner_sign +1 keeps
    # l > -0.10); left arm curls up (clockwise, torso on its counter-clockwise side)
    return compose(curl(SHOULDER, arm_r, 25.0, +1), curl(mirror(SHOULDER), arm_l, -25.0, -1),
                   lambda x: rk4_flow(x, swirl), lambda x: rk4_flow(x, bend))


def figure_stretch():
    rates = np.log(np.array([1.15, 0.9]))
    return compose(lambda x: rk4_flow(x, lambda y, t: stretch_rates(y, rates)),
                   similarity(rot2(math.radians(5.0)), (0.04, -0.03), (0.0, 0.0)))


# ---------------------------------------------------------------------------------------------
# pairs
# ---------------------------------------------------------------------------------------------

PAIRS = {
    "creature_articulated": (3, "creature", creature_articulated,
                             "creature: arm 0 curled up 32 deg, arm 2 down 25 deg, arm 3 swung "
                             "22 deg in the plane, each about a joint 0.33 from the centre with a "
                             "smooth weight along the arm (skeleton-driven smooth flow)"),
    "creature_arm_up": (3, "creature", creature_arm_up,
                        "creature: arm 0 raised 100 deg out of the plane (past the vertical) "
                        "about a joint 0.33 from the centre (large articulated motion)"),
    "creature_swirl": (3, "creature", creature_swirl,
                       "creature: arm 1 twisted about its axis (up to 50 deg at the tip), a "
                       "pinwheel swirl about z by 16 rho^2 deg (14 deg at the arms' ends), and a "
                       "cupping bend z += 0.14 rho^2"),
    "creature_stretch": (3, "creature", creature_stretch,
                         "creature: anisotropic stretch about 1.15 x 0.9 x 1.0 (rate +-25 % "
                         "smooth variation), then a 6 deg rotation and a translation "
                         "(0.06, -0.04, 0.03)"),
    "figure_articulated": (2, "figure", figure_articulated,
                           "figure: right arm raised 30 deg at the shoulder, left forearm "
                           "turned out 30 deg at the elbow, smooth weight along each limb "
                           "(skeleton-driven smooth flow)"),
    "figure_arms_up": (2, "figure", figure_arms_up,
                       "figure: both arms raised 60 deg at the shoulders, from hanging at the "
                       "sides to about horizontal (large articulated motion)"),
    "figure_swirl": (2, "figure", figure_swirl,
                     "figure: both arms curled up (angle growing along the arm to about 35 "
                     "deg), a swirl about the chest growing to 12 deg, a sideways bend "
                     "x += 0.12 (y - 0.1)^2"),
    "figure_stretch": (2, "figure", figure_stretch,
                       "figure: anisotropic stretch about 1.15 x 0.9 (rate +-25 % smooth "
                       "variation), then a 5 deg rotation and a translation (0.04, -0.03)"),
    "animal_head_turn": (3, "animal", animal_head_turn,
                         "animal: the head on its neck turned 30 deg sideways about the vertical "
                         "through the neck's base (skeleton-driven smooth flow)"),
    "animal_tail_swing": (3, "animal", animal_tail_swing,
                          "animal: the tail swung 40 deg sideways about the vertical through its "
                          "root"),
    "animal_torso_twist": (3, "animal", animal_torso_twist,
                           "animal: the torso twisted about its long axis, -11 deg at the hips "
                           "to +11 deg at the shoulders, legs, neck and tail following"),
    "animal_body_bend": (3, "animal", animal_body_bend,
                         "animal: the head turned 22 deg sideways on its neck, then the spine "
                         "bent 16 deg sideways (-8 deg at the hips to +8 deg at the shoulders), "
                         "legs, neck, head and tail following"),
    "animal_leg_swing": (3, "animal", animal_leg_swing,
                         "animal: the front right leg swung 90 deg forward at the shoulder, "
                         "from standing to horizontal (large articulated motion)"),
    "figure_arms_horizontal": (2, "figure", figure_arms_horizontal,
                               "figure: both arms raised 90 deg at the shoulders, from hanging "
                               "to horizontal (large articulated motion)"),
    "figure_legs_spread": (2, "figure", figure_legs_spread,
                           "figure: both legs swung out 25 deg at the hips (large articulated "
                           "motion)"),
    "figure_knees_bent": (2, "figure", figure_knees_bent,
                          "figure: thighs out 22 deg at the hips, shins back in 40 deg at the "
                          "knees, a frontal squat (large articulated motion)"),
    "figure_star": (2, "figure", figure_star,
                    "figure: a star jump, arms raised 90 deg and legs spread 20 deg (large "
                    "articulated motion)"),
}


SHAPES_3D = {"creature": creature_mesh, "animal": animal_mesh}

# What each pair tests (pair.json "kind"; the correspondence issue's goals differ by kind):
# near-isometric articulated or bending motion, large articulated motion (a limb swung 60 deg
# or more), or a stretch (not isometric).
LARGE_MOTION = ("creature_arm_up", "figure_arms_up", "animal_leg_swing", "figure_arms_horizontal",
                "figure_legs_spread", "figure_knees_bent", "figure_star")
STRETCH = ("creature_stretch", "figure_stretch")


def kind_of(name):
    return ("large motion" if name in LARGE_MOTION else
            "stretch" if name in STRETCH else "near-isometric")


# Named sets for --list and the benchmarks' --pairs: "speed", the eight pairs of the speed
# issue's accuracy benchmark (a creature and a figure, four motions each); "all".
SETS = {
    "speed": ("creature_articulated", "creature_arm_up", "creature_swirl", "creature_stretch",
              "figure_articulated", "figure_arms_up", "figure_swirl", "figure_stretch"),
}


def fmt_rows(points):
    f = " ".join(["%.{}f".format(DECIMALS)] * points.shape[1]) + "\n"
    return [f % tuple(p) for p in points]


def write_atomic(path, text):
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def write_obj(path, points, tris, title):
    rows = fmt_rows(points)
    text = ["# %s (bench/accuracy/make_pairs.py); %d vertices, %d triangles\n"
            % (title, len(points), len(tris))]
    text += ["v " + r for r in rows]
    text += ["f %d %d %d\n" % tuple(t + 1) for t in tris]
    write_atomic(path, "".join(text))


def write_polyline(path, poly, title):
    write_atomic(path, mea.POLYLINE_HEADER + "# %s (bench/accuracy/make_pairs.py); %d points, "
                 "counter-clockwise\n" % (title, len(poly)) + "".join(fmt_rows(poly)))


def probe_grid(points, count):
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 0.1 * (hi - lo).max()
    axes = [np.linspace(lo[a] - pad, hi[a] + pad, count) for a in range(points.shape[1])]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, points.shape[1])


LANDMARKS = 5  # landmark pairs written per pair (bench_accuracy.sh --landmarks)
RESAMPLE_FRACTION = 0.93  # 2D: points of the resampled target per source point


def resampled_target(target, tris, edge):
    """The target surface sampled independently of the source's vertices, as a scan of the posed
    shape would be: 3D, the zero level set of the target mesh's signed distance (OpenVDB, voxel
    = the mean edge length) meshed again; 2D, the closed curve resampled uniformly by arc length
    with 7% fewer points, starting half a spacing off."""
    if tris is None:
        closed = np.vstack([target, target[:1]])
        seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        count = int(round(RESAMPLE_FRACTION * len(target)))
        t = (np.arange(count) + 0.5) * s[-1] / count
        return np.stack([np.interp(t, s, closed[:, 0]), np.interp(t, s, closed[:, 1])], -1), None
    import pyopenvdb as vdb
    xform = vdb.createLinearTransform(voxelSize=float(edge))
    grid = vdb.FloatGrid.createLevelSetFromPolygons(target.astype(np.float32),
                                                    triangles=tris.astype(np.int32),
                                                    transform=xform, halfWidth=3.0)
    points, triangles, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
    quads = np.asarray(quads, dtype=np.int64).reshape(-1, 4)
    faces = np.concatenate([np.asarray(triangles, dtype=np.int64).reshape(-1, 3),
                            quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return np.asarray(points, dtype=float), faces


def scan_target(resampled, diagonal, name):
    """The resampled target as a scanner would return it: independent Gaussian noise of std
    SCAN_NOISE x the source's box diagonal on every coordinate of every vertex (0.2%: about 4 mm
    on a 2 m figure, the order of a consumer depth camera's error), seeded by the pair's name
    so that every run of the generator writes the same file; rounded to DECIMALS."""
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    noisy = resampled + rng.normal(0.0, SCAN_NOISE * diagonal, resampled.shape)
    return np.round(noisy, DECIMALS)


def landmark_indices(points, count=LANDMARKS):
    """Farthest-point sampling from the vertex farthest from the centroid, deterministic:
    mostly extremities (limb tips, head, feet), but on the figure the crotch comes before the
    left foot and on the animal a point of the flank before two of its feet."""
    chosen = [int(np.argmax(np.linalg.norm(points - points.mean(axis=0), axis=1)))]
    dist = np.linalg.norm(points - points[chosen[0]], axis=1)
    while len(chosen) < count:
        k = int(np.argmax(dist))
        chosen.append(k)
        dist = np.minimum(dist, np.linalg.norm(points - points[k], axis=1))
    return chosen


def write_landmarks(path, points):
    names = "xyz"[:points.shape[1]]
    rows = "".join(",".join("%.*f" % (DECIMALS, v) for v in p) + "\n" for p in points)
    write_atomic(path, ",".join(names) + "\n" + rows)


def make_pair(name, out_dir, shapes):
    dim, shape, make_g, description = PAIRS[name]
    t0 = time.time()
    g = make_g()
    points, tris = shapes[shape]
    target = np.round(g(points), DECIMALS)
    det_vertices = min_jacobian(g, points)
    det_grid = min_jacobian(g, probe_grid(points, JACOBIAN_GRID[0 if dim == 3 else 1]))
    if not (det_vertices > 0.0 and det_grid > 0.0):
        raise RuntimeError("%s: g folds (min det Dg %g on the vertices, %g on the grid)"
                           % (name, det_vertices, det_grid))
    info = {}
    if dim == 3:
        check_closed_oriented(target, tris, name + " target")
        crossings, tested = self_intersections(target, tris)
        if crossings:
            raise RuntimeError("%s: target intersects itself (%d crossings)" % (name, crossings))
        info["selfIntersectionPairsTested"] = tested
    else:
        if mea.signed_area(target) <= 0.0 or not mea.is_simple(target):
            raise RuntimeError("%s: target not counter-clockwise or not simple" % name)
    motion = np.linalg.norm(target - points, axis=1)
    diag = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    d = os.path.join(out_dir, name)
    os.makedirs(d, exist_ok=True)
    if dim == 3:
        write_obj(os.path.join(d, "source.obj"), points, tris, name + " source")
        write_obj(os.path.join(d, "target.obj"), target, tris, name + " target = g(source)")
        seg = np.linalg.norm(points[edges_of(tris)[:, 0]] - points[edges_of(tris)[:, 1]], axis=1)
    else:
        write_polyline(os.path.join(d, "source.polyline"), points, name + " source")
        write_polyline(os.path.join(d, "target.polyline"), target, name + " target = g(source)")
        seg = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    write_atomic(os.path.join(d, "truth.xyz"), "".join(fmt_rows(target)))
    # The target sampled independently (for point and mesh methods, which would otherwise read
    # the correspondence off the shared sampling).
    resampled, rtris = resampled_target(target, tris, seg.mean())
    if dim == 3:
        write_obj(os.path.join(d, "target_resampled.obj"), np.round(resampled, DECIMALS), rtris,
                  name + " target, re-meshed from its level set")
    else:
        write_polyline(os.path.join(d, "target_resampled.polyline"),
                       np.round(resampled, DECIMALS), name + " target, resampled by arc length")
    info["resampledTargetVertices"] = int(len(resampled))
    # The same with a scanner's noise on every vertex (bench_accuracy.sh --scan).
    scan = scan_target(resampled, diag, name)
    if dim == 3:
        write_obj(os.path.join(d, "target_scan.obj"), scan, rtris,
                  name + " target, re-meshed, noise %.3g of the diagonal" % SCAN_NOISE)
    else:
        write_polyline(os.path.join(d, "target_scan.polyline"), scan,
                       name + " target, resampled, noise %.3g of the diagonal" % SCAN_NOISE)
    info["scanNoiseWorld"] = SCAN_NOISE * diag
    # Landmarks for vdb_match --landmarks: extremities of the source and their true images.
    marks = landmark_indices(points)
    write_landmarks(os.path.join(d, "landmarks_source.csv"), points[marks])
    write_landmarks(os.path.join(d, "landmarks_target.csv"), target[marks])
    box = points.max(axis=0) - points.min(axis=0)
    pair = {
        "name": name,
        "dimension": dim,
        "shape": shape,
        "kind": kind_of(name),
        "description": description,
        "vertices": int(len(points)),
        "elements": int(len(tris)) if dim == 3 else int(len(points)),
        "sourceBoxMin": points.min(axis=0).tolist(),
        "sourceBoxMax": points.max(axis=0).tolist(),
        "sourceBoxDiagonal": diag,
        "edgeLength": {"mean": float(seg.mean()), "max": float(seg.max()),
                       "meanOverBoxSide": float(seg.mean() / box.max()),
                       "maxOverBoxSide": float(seg.max() / box.max())},
        "motion": {"meanWorld": float(motion.mean()), "maxWorld": float(motion.max()),
                   "meanFractionOfDiagonal": float(motion.mean() / diag),
                   "maxFractionOfDiagonal": float(motion.max() / diag)},
        "minDetDg": {"vertices": det_vertices, "grid": det_grid},
        "flowSteps": FLOW_STEPS,
    }
    pair.update(info)
    write_atomic(os.path.join(d, "pair.json"), json.dumps(pair, indent=2) + "\n")
    print("%-21s %dD %6d vertices, motion mean %.4f max %.4f (%.1f%% / %.1f%% of the diagonal), "
          "min det Dg %.3f, %.1fs" % (name, dim, len(points), motion.mean(), motion.max(),
                                      100 * motion.mean() / diag, 100 * motion.max() / diag,
                                      min(det_vertices, det_grid), time.time() - t0))


def main():
    args = sys.argv[1:]
    usage = "usage: make_pairs.py OUTDIR [--only NAME[,NAME...]] | --list [all|speed]"
    if "--list" in args:
        at = args.index("--list")
        which = args[at + 1] if at + 1 < len(args) else "all"
        if which != "all" and which not in SETS:
            sys.exit("make_pairs.py: unknown set %s; choose from all, %s"
                     % (which, ", ".join(SETS)))
        print("\n".join(PAIRS if which == "all" else SETS[which]))
        return
    selected = list(PAIRS)
    if "--only" in args:
        at = args.index("--only")
        if at + 1 >= len(args):
            sys.exit(usage)
        selected = [s for s in args[at + 1].split(",") if s]
        del args[at:at + 2]
        unknown = [s for s in selected if s not in PAIRS]
        if unknown:
            sys.exit("make_pairs.py: unknown pair(s) %s; choose from %s"
                     % (", ".join(unknown), ", ".join(PAIRS)))
    if len(args) != 1 or args[0].startswith("-"):
        sys.exit(usage)
    out_dir = args[0]
    os.makedirs(out_dir, exist_ok=True)
    shapes = {}
    for shape in sorted({PAIRS[s][1] for s in selected}):
        t0 = time.time()
        if shape == "figure":
            poly = figure_polyline()
            if mea.signed_area(poly) <= 0.0 or not mea.is_simple(poly):
                raise RuntimeError("figure: not counter-clockwise or not simple")
            shapes[shape] = (poly, None)
            continue
        points, tris = SHAPES_3D[shape]()
        check_closed_oriented(points, tris, shape)
        crossings, tested = self_intersections(points, tris)
        if crossings:
            raise RuntimeError("%s: mesh intersects itself (%d crossings)" % (shape, crossings))
        shapes[shape] = (points, tris)
        print("%s: %d vertices, %d triangles, closed, outward, no self-intersection "
              "(%d edge-triangle pairs tested), %.1fs" % (shape, len(points), len(tris), tested,
                                                         time.time() - t0))
    for name in selected:
        make_pair(name, out_dir, shapes)


if __name__ == "__main__":
    main()
