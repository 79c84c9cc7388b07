#!/usr/bin/env python3
"""Writes the example inputs of vdb_match into assets/.

3D inputs are signed-distance level sets (FloatGrid, class "level set", name "surface", negative
inside, 3-voxel narrow band, world units), like Houdini's "VDB from Polygons":

- sphere.vdb:    radius 1 centred at the origin, voxel size 0.06, transform a pure scale;
- ellipsoid.vdb: semi-axes (1.35, 0.95, 0.8) rotated by 25 degrees about z, centred at
                 (0.3, 0.15, -0.1) (shifted and scaled relative to the sphere), made from a
                 polygon mesh with createLevelSetFromPolygons; voxel size 0.05 and a transform
                 with a rotation (20 degrees about x) and a translation.

  The different voxel sizes and transforms exercise vdb_match's placement in the unit box.

- starfish_a.vdb, starfish_b.vdb: a starfish-like creature in two poses (cf. the paper's
  starfish example). Pose A: smooth union (log-sum-exp, width STARFISH_BLEND) of a central
  sphere and five round cones (arms tapering from radius STARFISH_ARM_BASE_RADIUS to
  STARFISH_ARM_TIP_RADIUS, tips STARFISH_ARM_LENGTH from the centre, arm 0 along +y), the whole
  flattened by STARFISH_FLATTEN in z. Its closed mesh is a UV sphere of rays from the centre
  projected onto that implicit surface (star-shaped: checked). Pose B is the same mesh moved by
  a smooth space deformation: per STARFISH_BENDS, the flow of a windowed rotation field (arm 0
  curled up 40 degrees, arm 1 up 15, arm 2 down 30, arm 3 swung 20 degrees sideways in the
  plane), then a rigid rotation (STARFISH_B_ROTATION_DEG) and translation. Flows of smooth
  fields are diffeomorphisms, so pose B is closed and free of self-intersections; the script
  also checks that the Jacobian determinant is positive on the mesh and in its bounding box.
  Both: createLevelSetFromPolygons, voxel size STARFISH_VOXEL (about 80 voxels across), pure
  scale transform. starfish_a.obj (pose A mesh) is written only if under OBJ_MAX_BYTES.

2D inputs (cf. the paper's "jump" example):

- figure_a.polyline, figure_b.polyline: a person-like silhouette (head, neck, torso, two arms
  with hands, two legs with feet), pose A standing with arms slightly out, pose B jumping
  with arms raised halfway to the side (about 35 degrees) and legs apart. Zero contour of a smooth union (width FIGURE_BLEND) of 2D round cones
  (FIGURE_BODY, FIGURE_LIMBS), extracted by marching squares (spacing FIGURE_CONTOUR_SPACING)
  and resampled uniformly in arc length to FIGURE_POINTS points; checked to be a single closed
  curve, counter-clockwise and without self-intersections. Text format: see POLYLINE_HEADER.
- figure_a_slice.vdb, figure_b_slice.vdb: the same curves as 2D level sets: FloatGrid, class
  level set, name "surface", all active voxels in the k = 0 layer (world z = 0), signed
  distance to the polyline (negative inside) where below 3 voxels, inactive voxels of that
  layer inside at -background; voxel size FIGURE_SLICE_VOXEL (about 150 voxels tall).

Needs pyopenvdb and numpy (Debian 12: python3-openvdb, python3-numpy; run with the system
python, e.g. /usr/bin/python3). Usage:

    make_example_assets.py [--only NAME[,NAME...]] [OUTPUT_DIR]

NAME is one of sphere, ellipsoid, starfish, figure (default: all); OUTPUT_DIR defaults to
assets/ next to this script's parent directory. Regenerated files have the same contents; .vdb
files differ only in the file UUID that OpenVDB writes into every header (so, to leave the
committed sphere.vdb and ellipsoid.vdb untouched, use e.g. --only starfish,figure). The
starfish takes about a minute, the figures about half a minute.
"""

import math
import os
import sys

import numpy as np
import pyopenvdb as vdb

HALF_WIDTH = 3.0  # narrow band half width, voxels

SPHERE_RADIUS = 1.0
SPHERE_VOXEL = 0.06

ELLIPSOID_AXES = (1.35, 0.95, 0.8)
ELLIPSOID_CENTRE = (0.3, 0.15, -0.1)
ELLIPSOID_ROTATION_Z_DEG = 25.0
ELLIPSOID_VOXEL = 0.05
ELLIPSOID_GRID_ROTATION_X_DEG = 20.0
ELLIPSOID_GRID_TRANSLATION = (0.013, -0.021, 0.007)
# Mesh resolution: facets much smaller than a voxel (longest circumference / 400).
MESH_LATITUDES = 128
MESH_LONGITUDES = 256


def ellipsoid_mesh():
    """A closed UV-sphere mesh of the ellipsoid: quads between rings, triangles at the poles."""
    a = np.array(ELLIPSOID_AXES)
    theta = np.pi * np.arange(1, MESH_LATITUDES) / MESH_LATITUDES  # ring polar angles
    phi = 2.0 * np.pi * np.arange(MESH_LONGITUDES) / MESH_LONGITUDES
    t, p = np.meshgrid(theta, phi, indexing="ij")
    unit = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    rings = unit.reshape(-1, 3)
    points = np.vstack([[0.0, 0.0, 1.0], rings, [0.0, 0.0, -1.0]]) * a
    c, s = math.cos(math.radians(ELLIPSOID_ROTATION_Z_DEG)), math.sin(
        math.radians(ELLIPSOID_ROTATION_Z_DEG))
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    points = points @ rot.T + np.array(ELLIPSOID_CENTRE)

    m = MESH_LONGITUDES
    north, south = 0, 1 + (MESH_LATITUDES - 1) * m

    def vid(ring, j):
        return 1 + ring * m + (j % m)

    quads = [[vid(r, j), vid(r + 1, j), vid(r + 1, j + 1), vid(r, j + 1)]
             for r in range(MESH_LATITUDES - 2) for j in range(m)]
    last = MESH_LATITUDES - 2
    triangles = [[north, vid(0, j), vid(0, j + 1)] for j in range(m)]
    triangles += [[south, vid(last, j + 1), vid(last, j)] for j in range(m)]
    return (points.astype(np.float32), np.array(triangles, dtype=np.uint32),
            np.array(quads, dtype=np.uint32))


def rotation_x_transform(voxel, degrees, translation):
    """4x4 (row-vector convention, as OpenVDB) of scale * rotation about x, then translation."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return [[voxel, 0.0, 0.0, 0.0],
            [0.0, voxel * c, voxel * s, 0.0],
            [0.0, -voxel * s, voxel * c, 0.0],
            [translation[0], translation[1], translation[2], 1.0]]


def finish(grid):
    grid.name = "surface"
    grid.gridClass = vdb.GridClass.LEVEL_SET
    return grid


# ---------------------------------------------------------------------------------------------
# Starfish (3D): five tapered, flattened arms around a round body, in two poses.
# ---------------------------------------------------------------------------------------------

STARFISH_ARMS = 5
STARFISH_BODY_RADIUS = 0.30       # sphere at the centre (before flattening)
STARFISH_ARM_LENGTH = 0.90        # centre to the centre of the rounded tip
STARFISH_ARM_BASE_RADIUS = 0.22   # round cone radius at the centre ...
STARFISH_ARM_TIP_RADIUS = 0.095   # ... and at the tip
STARFISH_FLATTEN = 0.7            # z scale of the whole shape (a flattened creature)
STARFISH_BLEND = 0.03             # smooth-union width (log-sum-exp), world units
STARFISH_VOXEL = 0.024            # ~80 voxels across the largest extent
# Mesh: rays from the centre on a UV sphere, projected onto the implicit surface.
STARFISH_LATITUDES = 160
STARFISH_LONGITUDES = 768
# Pose B: smooth flows (RK4-integrated velocity fields, so a diffeomorphism with positive
# Jacobian), one per bent arm, then a rigid motion. (arm index, kind, degrees); arm 0 points
# along +y, arms counted counter-clockwise seen from +z. "up"/"down": curl about a horizontal
# axis across the arm (pivot STARFISH_BEND_PIVOT from the centre); "swing": rotation in the
# plane about a vertical axis through the pivot.
STARFISH_BENDS = ((0, "up", 40.0), (1, "up", 15.0), (2, "down", 30.0), (3, "swing", 20.0))
STARFISH_BEND_PIVOT = 0.33        # distance from the centre of the bend pivot along the arm
STARFISH_BEND_START = 0.45        # arm distance where the bend window reaches one half
STARFISH_BEND_RAMP = 0.055        # logistic width of that window
STARFISH_BEND_WIDTH = 0.26        # lateral half width of the window (exp(-(d/w)^4))
STARFISH_BEND_STEPS = 24          # RK4 steps per flow
OBJ_MAX_BYTES = 300 * 1024     # starfish_a.obj is written only when smaller than this
STARFISH_B_ROTATION_DEG = (8.0, -5.0, 14.0)  # rigid rotation of pose B about x, then y, then z
STARFISH_B_TRANSLATION = (0.09, -0.06, 0.04)


def arm_directions():
    ang = np.pi / 2 + 2.0 * np.pi * np.arange(STARFISH_ARMS) / STARFISH_ARMS
    return np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=-1)


def sd_round_cone(p, a, b, r1, r2):
    """Signed distance (any dimension) to the round cone between spheres (a, r1) and (b, r2)."""
    ba = b - a
    l2 = ba @ ba
    rr = r1 - r2
    a2 = l2 - rr * rr
    il2 = 1.0 / l2
    pa = p - a
    y = pa @ ba
    z = y - l2
    x2 = np.sum((pa * l2 - y[..., None] * ba) ** 2, axis=-1)
    y2 = y * y * l2
    z2 = z * z * l2
    k = np.sign(rr) * rr * rr * x2
    d_tip = np.sqrt(x2 + z2) * il2 - r2
    d_base = np.sqrt(x2 + y2) * il2 - r1
    d_side = (np.sqrt(np.maximum(x2 * a2 * il2, 0.0)) + y * rr) * il2 - r1
    return np.where(np.sign(z) * a2 * z2 > k, d_tip, np.where(np.sign(y) * a2 * y2 < k, d_base,
                                                              d_side))


def smooth_union(distances, blend):
    """C-infinity smooth minimum (log-sum-exp) of a list of distance arrays."""
    d = np.stack(distances)
    m = d.min(axis=0)
    return m - blend * np.log(np.sum(np.exp(-(d - m) / blend), axis=0))


def starfish_function(p):
    """Implicit function of pose A (negative inside; a distance only approximately)."""
    q = p * np.array([1.0, 1.0, 1.0 / STARFISH_FLATTEN])
    origin = np.zeros(3)
    parts = [np.linalg.norm(q, axis=-1) - STARFISH_BODY_RADIUS]
    for d in arm_directions():
        parts.append(sd_round_cone(q, origin, STARFISH_ARM_LENGTH * d, STARFISH_ARM_BASE_RADIUS,
                                   STARFISH_ARM_TIP_RADIUS))
    return smooth_union(parts, STARFISH_BLEND)


def starfish_mesh_a():
    """Pose A as a closed UV-sphere mesh: every ray from the centre meets the (star-shaped)
    surface once; the vertex on a ray is found by bisection. Returns points, triangles, quads."""
    theta = np.pi * np.arange(1, STARFISH_LATITUDES) / STARFISH_LATITUDES
    phi = 2.0 * np.pi * np.arange(STARFISH_LONGITUDES) / STARFISH_LONGITUDES
    t, p = np.meshgrid(theta, phi, indexing="ij")
    rays = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    rays = np.vstack([[0.0, 0.0, 1.0], rays.reshape(-1, 3), [0.0, 0.0, -1.0]])
    far = STARFISH_ARM_LENGTH + STARFISH_ARM_TIP_RADIUS + 0.2
    # Star-shapedness: along every ray the function changes sign exactly once.
    samples = np.linspace(0.0, far, 96)
    for chunk in np.array_split(np.arange(len(rays)), 32):
        f = starfish_function(rays[chunk, None, :] * samples[None, :, None])
        changes = np.count_nonzero(np.diff(np.sign(f), axis=1), axis=1)
        if not np.all(changes == 1):
            raise RuntimeError("starfish pose A is not star-shaped from its centre")
    lo = np.zeros(len(rays))
    hi = np.full(len(rays), far)
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        inside = starfish_function(rays * mid[:, None]) < 0.0
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    points = rays * (0.5 * (lo + hi))[:, None]

    m = STARFISH_LONGITUDES
    north, south = 0, 1 + (STARFISH_LATITUDES - 1) * m

    def vid(ring, j):
        return 1 + ring * m + (j % m)

    quads = [[vid(r, j), vid(r + 1, j), vid(r + 1, j + 1), vid(r, j + 1)]
             for r in range(STARFISH_LATITUDES - 2) for j in range(m)]
    last = STARFISH_LATITUDES - 2
    triangles = [[north, vid(0, j), vid(0, j + 1)] for j in range(m)]
    triangles += [[south, vid(last, j + 1), vid(last, j)] for j in range(m)]
    return points, np.array(triangles, dtype=np.uint32), np.array(quads, dtype=np.uint32)


def rotation_matrix(axis, radians):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(radians) * k + (1.0 - math.cos(radians)) * (k @ k)


def bend_flow(points, arm, kind, degrees):
    """Flow over t in [0, 1] of v(x, t) = w * W(R(t)^-1 (x - c)) * (a x (x - c)): rotation with
    rate w = angle about axis a through the pivot c, weighted by a window W that moves with the
    rotation (so the arm beyond the window's ramp turns by the full angle, its base bends
    smoothly, and the rest of the body stays). Smooth in x for every t: a diffeomorphism."""
    d = arm_directions()[arm]
    up = np.array([0.0, 0.0, 1.0])
    if kind == "swing":
        axis = up
    else:
        axis = np.cross(d, up) * (1.0 if kind == "up" else -1.0)
    omega = math.radians(degrees)
    centre = STARFISH_BEND_PIVOT * d
    lateral_dir = np.cross(up, d)

    def velocity(x, t):
        back = (x - centre) @ rotation_matrix(axis, -omega * t).T + centre  # window frame
        s = back @ d
        lat = back @ lateral_dir
        w = 1.0 / (1.0 + np.exp(-(s - STARFISH_BEND_START) / STARFISH_BEND_RAMP))
        w = w * np.exp(-(lat / STARFISH_BEND_WIDTH) ** 4)
        return omega * w[:, None] * np.cross(axis, x - centre)

    x = np.array(points, dtype=float)
    h = 1.0 / STARFISH_BEND_STEPS
    for i in range(STARFISH_BEND_STEPS):
        t = i * h
        k1 = velocity(x, t)
        k2 = velocity(x + 0.5 * h * k1, t + 0.5 * h)
        k3 = velocity(x + 0.5 * h * k2, t + 0.5 * h)
        k4 = velocity(x + h * k3, t + h)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def starfish_pose_b(points):
    """The space deformation taking pose A to pose B (bends, then the rigid motion)."""
    x = np.array(points, dtype=float)
    for arm, kind, degrees in STARFISH_BENDS:
        x = bend_flow(x, arm, kind, degrees)
    rx, ry, rz = (math.radians(a) for a in STARFISH_B_ROTATION_DEG)
    rot = rotation_matrix((0, 0, 1), rz) @ rotation_matrix((0, 1, 0), ry) @ rotation_matrix(
        (1, 0, 0), rx)
    return x @ rot.T + np.array(STARFISH_B_TRANSLATION)


def min_jacobian(deformation, points, step=1e-4):
    """Smallest determinant of the central-difference Jacobian of deformation at points."""
    cols = []
    for axis in range(3):
        e = np.zeros(3)
        e[axis] = step
        cols.append((deformation(points + e) - deformation(points - e)) / (2.0 * step))
    return float(np.linalg.det(np.stack(cols, axis=-1)).min())


def write_obj(path, points, triangles, quads):
    with open(path, "w") as f:
        f.write("# starfish pose A (tools/make_example_assets.py)\n")
        f.writelines("v %.5f %.5f %.5f\n" % tuple(p) for p in points)
        f.writelines("f %d %d %d\n" % tuple(t + 1) for t in triangles)
        f.writelines("f %d %d %d %d\n" % tuple(q + 1) for q in quads)


def starfish_grids():
    points, triangles, quads = starfish_mesh_a()
    points_b = starfish_pose_b(points)
    rng = np.random.default_rng(1)
    lo, hi = points.min(axis=0) - 0.1, points.max(axis=0) + 0.1
    probes = np.vstack([points[::7], lo + (hi - lo) * rng.random((20000, 3))])
    det = min_jacobian(starfish_pose_b, probes)
    if det <= 0.0:
        raise RuntimeError("pose B deformation folds (Jacobian %g)" % det)
    print("starfish: %d vertices, pose B deformation min Jacobian %.3f" % (len(points), det))
    xform = vdb.createLinearTransform(voxelSize=STARFISH_VOXEL)
    grids = []
    for pts in (points, points_b):
        grids.append(finish(vdb.FloatGrid.createLevelSetFromPolygons(
            pts.astype(np.float32), triangles=triangles, quads=quads, transform=xform.deepCopy(),
            halfWidth=HALF_WIDTH)))
    return grids, (points, triangles, quads)


# ---------------------------------------------------------------------------------------------
# Figure (2D): a person-like silhouette (head, body, two arms, two legs) in two poses.
# ---------------------------------------------------------------------------------------------

# Each pose: round cones (2D capsules with linearly varying radius) between points, as
# (x0, y0, r0, x1, y1, r1); mirrored limbs are listed for the right side (x > 0) and copied to
# the left. World units; the figure is about 1.9 tall.
FIGURE_BODY = (
    (0.0, 0.76, 0.135, 0.0, 0.74, 0.135),     # head
    (0.0, 0.62, 0.055, 0.0, 0.50, 0.06),      # neck
    (0.0, 0.40, 0.16, 0.0, 0.05, 0.125),      # torso
)
FIGURE_LIMBS = {
    "a": (  # standing, arms slightly out, feet a little apart
        (0.15, 0.44, 0.075, 0.33, 0.22, 0.066),   # upper arm
        (0.33, 0.22, 0.066, 0.45, -0.02, 0.058),  # forearm
        (0.45, -0.02, 0.062, 0.47, -0.07, 0.06),  # hand
        (0.08, 0.03, 0.10, 0.13, -0.44, 0.08),    # thigh
        (0.13, -0.44, 0.08, 0.15, -0.90, 0.065),  # shin
        (0.15, -0.93, 0.06, 0.24, -0.95, 0.05),   # foot
    ),
    "b": (  # jumping: arms raised halfway to the side, legs apart
        (0.15, 0.44, 0.075, 0.37, 0.31, 0.066),
        (0.37, 0.31, 0.066, 0.56, 0.14, 0.058),
        (0.56, 0.14, 0.062, 0.60, 0.11, 0.06),
        (0.08, 0.03, 0.10, 0.18, -0.43, 0.08),
        (0.18, -0.43, 0.08, 0.24, -0.89, 0.065),
        (0.24, -0.92, 0.06, 0.33, -0.94, 0.05),
    ),
}
FIGURE_BLEND = 0.012          # smooth-union width (log-sum-exp), world units
FIGURE_CONTOUR_SPACING = 0.002  # marching-squares grid spacing
FIGURE_POINTS = 560           # points per polyline (uniform in arc length)
FIGURE_SLICE_VOXEL = 0.0125   # ~150 voxels across the height
POLYLINE_HEADER = """\
# vdbmatch polyline: lines "x y" in world units, '#' starts a comment, blank lines separate
# closed curves, the last point connects back to the first (not repeated), at least 3 points
# per curve.
"""


def figure_function(p, pose):
    parts = []
    limbs = FIGURE_LIMBS[pose]
    cones = list(FIGURE_BODY) + list(limbs) + [(-c[0], c[1], c[2], -c[3], c[4], c[5])
                                               for c in limbs]
    for x0, y0, r0, x1, y1, r1 in cones:
        parts.append(sd_round_cone(p, np.array([x0, y0]), np.array([x1, y1]), r0, r1))
    return smooth_union(parts, FIGURE_BLEND)


def zero_contours(values, x, y):
    """Marching squares on values[j, i] sampled at (x[i], y[j]); returns the closed zero
    contours as lists of points (no saddle cells allowed)."""
    inside = values < 0.0
    crossings = {}  # edge key -> point

    def crossing(key):
        if key not in crossings:
            kind, j, i = key
            j2, i2 = (j, i + 1) if kind == "h" else (j + 1, i)
            a, b = values[j, i], values[j2, i2]
            t = a / (a - b)
            crossings[key] = (x[i] + t * (x[i2] - x[i]), y[j] + t * (y[j2] - y[j]))
        return crossings[key]

    neighbours = {}
    ny, nx = values.shape
    cells = np.argwhere((inside[:-1, :-1] != inside[:-1, 1:]) | (inside[:-1, :-1] != inside[1:, :-1])
                        | (inside[:-1, :-1] != inside[1:, 1:]))
    for j, i in cells:
        edges = []
        # counter-clockwise around the cell: bottom, right, top, left
        for key, (ja, ia), (jb, ib) in ((("h", j, i), (j, i), (j, i + 1)),
                                         (("v", j, i + 1), (j, i + 1), (j + 1, i + 1)),
                                         (("h", j + 1, i), (j + 1, i + 1), (j + 1, i)),
                                         (("v", j, i), (j + 1, i), (j, i))):
            if inside[ja, ia] != inside[jb, ib]:
                edges.append(key)
        if len(edges) != 2:
            raise RuntimeError("saddle cell in the contour extraction; move the grid")
        for a, b in ((edges[0], edges[1]), (edges[1], edges[0])):
            neighbours.setdefault(a, []).append(b)
    contours = []
    seen = set()
    for start in neighbours:
        if start in seen:
            continue
        loop, prev, cur = [], None, start
        while cur not in seen:
            seen.add(cur)
            loop.append(crossing(cur))
            nxt = [e for e in neighbours[cur] if e != prev]
            prev, cur = cur, nxt[0]
        contours.append(np.array(loop))
    return contours


def resample_closed(points, count):
    closed = np.vstack([points, points[:1]])
    seg = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.arange(count) * s[-1] / count
    return np.stack([np.interp(t, s, closed[:, 0]), np.interp(t, s, closed[:, 1])], axis=-1)


def signed_area(poly):
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def is_simple(poly):
    """True when no two non-adjacent segments of the closed polyline intersect."""
    a, b = poly, np.roll(poly, -1, axis=0)
    n = len(poly)

    def orient(p, q, r):
        return ((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
                - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))

    A, B = a[:, None, :], b[:, None, :]
    C, D = a[None, :, :], b[None, :, :]
    d1, d2 = orient(A, B, C), orient(A, B, D)
    d3, d4 = orient(C, D, A), orient(C, D, B)
    proper = (d1 * d2 < 0.0) & (d3 * d4 < 0.0)

    def on_segment(p, q, r, d):  # r lies on segment pq, given orient(p, q, r) == d
        return ((d == 0.0) & (np.minimum(p[..., 0], q[..., 0]) <= r[..., 0])
                & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
                & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1])
                & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1])))

    hit = (proper | on_segment(A, B, C, d1) | on_segment(A, B, D, d2) | on_segment(C, D, A, d3)
           | on_segment(C, D, B, d4))
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    adjacent = (i == j) | (np.abs(i - j) == 1) | (np.abs(i - j) == n - 1)
    return not np.any(hit & ~adjacent)


def figure_polyline(pose):
    h = FIGURE_CONTOUR_SPACING
    x = np.arange(-0.8, 0.8, h) + 0.3 * h   # offsets keep samples off the symmetry axis
    y = np.arange(-1.1, 1.2, h) + 0.3 * h
    gx, gy = np.meshgrid(x, y)
    values = figure_function(np.stack([gx, gy], axis=-1), pose)
    contours = zero_contours(values, x, y)
    if len(contours) != 1:
        raise RuntimeError("figure %s: %d contours, expected one" % (pose, len(contours)))
    poly = np.round(resample_closed(contours[0], FIGURE_POINTS), 6)  # as written to the file
    if signed_area(poly) < 0.0:
        poly = poly[::-1]
    if not is_simple(poly):
        raise RuntimeError("figure %s: polyline intersects itself" % pose)
    return poly


def write_polyline(path, poly, title):
    with open(path + ".tmp", "w") as f:
        f.write(POLYLINE_HEADER)
        f.write("# %s (tools/make_example_assets.py); %d points, counter-clockwise\n"
                % (title, len(poly)))
        f.writelines("%.6f %.6f\n" % (px, py) for px, py in poly)
    os.replace(path + ".tmp", path)


def polyline_signed_distance(poly, pts):
    """Distance from pts (n, 2) to the closed polyline, negative inside (even-odd rule)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    out = np.empty(len(pts))
    for chunk in np.array_split(np.arange(len(pts)), max(1, len(pts) // 2000)):
        p = pts[chunk][:, None, :]
        ab = b - a
        t = np.clip(np.sum((p - a) * ab, axis=-1) / np.sum(ab * ab, axis=-1), 0.0, 1.0)
        dist = np.linalg.norm(p - (a + t[..., None] * ab), axis=-1).min(axis=1)
        py = p[..., 1]
        straddle = (a[:, 1] > py) != (b[:, 1] > py)
        xcross = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(
            b[:, 1] == a[:, 1], 1.0, b[:, 1] - a[:, 1])
        inside = np.count_nonzero(straddle & (p[..., 0] < xcross), axis=1) % 2 == 1
        out[chunk] = np.where(inside, -dist, dist)
    return out


def slice_grid(poly):
    """Level set of the polyline in the k = 0 layer: active voxels where |distance| is below
    the band width; inactive voxels of that layer inside get -background."""
    voxel = FIGURE_SLICE_VOXEL
    band = HALF_WIDTH * voxel
    lo = np.floor(poly.min(axis=0) / voxel).astype(int) - 4
    hi = np.ceil(poly.max(axis=0) / voxel).astype(int) + 4
    ii, jj = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1), indexing="ij")
    ij = np.stack([ii.ravel(), jj.ravel()], axis=-1)
    d = polyline_signed_distance(poly, ij * voxel)
    grid = vdb.FloatGrid(background=band)
    grid.transform = vdb.createLinearTransform(voxelSize=voxel)
    acc = grid.getAccessor()
    for (i, j), v in zip(ij.tolist(), d.tolist()):
        if abs(v) < band:
            acc.setValueOn((i, j, 0), v)
        elif v < 0.0:
            acc.setValueOff((i, j, 0), -band)
    return finish(grid)


ASSETS = ("sphere", "ellipsoid", "starfish", "figure")


def write_vdb(path, grid):
    tmp = path + ".tmp"
    vdb.write(tmp, grids=[grid])
    os.replace(tmp, path)
    print("%s: %d active voxels, voxel size %g, %d bytes"
          % (path, grid.activeVoxelCount(), grid.transform.voxelSize()[0],
             os.path.getsize(path)))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    args = sys.argv[1:]
    selected = set(ASSETS)
    if "--only" in args:
        at = args.index("--only")
        if at + 1 >= len(args):
            sys.exit("usage: make_example_assets.py [--only NAME[,NAME...]] [OUTPUT_DIR]")
        selected = set(args[at + 1].split(","))
        del args[at:at + 2]
        unknown = selected - set(ASSETS)
        if unknown:
            sys.exit("unknown asset(s) %s; choose from %s" % (", ".join(sorted(unknown)),
                                                            ", ".join(ASSETS)))
    out_dir = args[0] if args else os.path.join(os.path.dirname(here), "assets")
    os.makedirs(out_dir, exist_ok=True)

    if "sphere" in selected:
        sphere = finish(vdb.createLevelSetSphere(radius=SPHERE_RADIUS, center=(0.0, 0.0, 0.0),
                                                 voxelSize=SPHERE_VOXEL, halfWidth=HALF_WIDTH))
        write_vdb(os.path.join(out_dir, "sphere.vdb"), sphere)

    if "ellipsoid" in selected:
        points, triangles, quads = ellipsoid_mesh()
        xform = vdb.createLinearTransform(
            rotation_x_transform(ELLIPSOID_VOXEL, ELLIPSOID_GRID_ROTATION_X_DEG,
                                 ELLIPSOID_GRID_TRANSLATION))
        ellipsoid = finish(vdb.FloatGrid.createLevelSetFromPolygons(
            points, triangles=triangles, quads=quads, transform=xform, halfWidth=HALF_WIDTH))
        write_vdb(os.path.join(out_dir, "ellipsoid.vdb"), ellipsoid)

    if "starfish" in selected:
        (grid_a, grid_b), (points, triangles, quads) = starfish_grids()
        write_vdb(os.path.join(out_dir, "starfish_a.vdb"), grid_a)
        write_vdb(os.path.join(out_dir, "starfish_b.vdb"), grid_b)
        obj = os.path.join(out_dir, "starfish_a.obj")
        write_obj(obj + ".tmp", points, triangles, quads)
        if os.path.getsize(obj + ".tmp") < OBJ_MAX_BYTES:
            os.replace(obj + ".tmp", obj)
            print("%s: %d bytes" % (obj, os.path.getsize(obj)))
        else:
            print("starfish_a.obj skipped: %d bytes (limit %d)"
                  % (os.path.getsize(obj + ".tmp"), OBJ_MAX_BYTES))
            os.remove(obj + ".tmp")

    if "figure" in selected:
        for pose in ("a", "b"):
            poly = figure_polyline(pose)
            path = os.path.join(out_dir, "figure_%s.polyline" % pose)
            write_polyline(path, poly, "figure, pose %s (%s)"
                           % (pose, "standing" if pose == "a" else "jumping"))
            print("%s: %d points, area %.4f, %d bytes"
                  % (path, len(poly), signed_area(poly), os.path.getsize(path)))
            write_vdb(os.path.join(out_dir, "figure_%s_slice.vdb" % pose), slice_grid(poly))


if __name__ == "__main__":
    main()
