#!/usr/bin/env python3
"""Writes the example inputs of vdb_match: assets/sphere.vdb and assets/ellipsoid.vdb.

Both are signed-distance level sets (FloatGrid, class "level set", name "surface", negative
inside, 3-voxel narrow band, world units), like Houdini's "VDB from Polygons":

- sphere.vdb:    radius 1 centred at the origin, voxel size 0.06, transform a pure scale;
- ellipsoid.vdb: semi-axes (1.35, 0.95, 0.8) rotated by 25 degrees about z, centred at
                 (0.3, 0.15, -0.1) (shifted and scaled relative to the sphere), made from a
                 polygon mesh with createLevelSetFromPolygons; voxel size 0.05 and a transform
                 with a rotation (20 degrees about x) and a translation.

The different voxel sizes and transforms exercise vdb_match's placement in the unit box.

Needs pyopenvdb and numpy (Debian 12: python3-openvdb, python3-numpy; run with the system
python, e.g. /usr/bin/python3). Usage: make_example_assets.py [OUTPUT_DIR] (default: assets/
next to this script's parent directory).
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


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(here), "assets")
    os.makedirs(out_dir, exist_ok=True)

    sphere = finish(vdb.createLevelSetSphere(radius=SPHERE_RADIUS, center=(0.0, 0.0, 0.0),
                                             voxelSize=SPHERE_VOXEL, halfWidth=HALF_WIDTH))

    points, triangles, quads = ellipsoid_mesh()
    xform = vdb.createLinearTransform(
        rotation_x_transform(ELLIPSOID_VOXEL, ELLIPSOID_GRID_ROTATION_X_DEG,
                             ELLIPSOID_GRID_TRANSLATION))
    ellipsoid = finish(vdb.FloatGrid.createLevelSetFromPolygons(
        points, triangles=triangles, quads=quads, transform=xform, halfWidth=HALF_WIDTH))

    for name, grid in (("sphere.vdb", sphere), ("ellipsoid.vdb", ellipsoid)):
        path = os.path.join(out_dir, name)
        tmp = path + ".tmp"
        vdb.write(tmp, grids=[grid])
        os.replace(tmp, path)
        print("%s: %d active voxels, voxel size %g, %d bytes"
              % (path, grid.activeVoxelCount(), grid.transform.voxelSize()[0],
                 os.path.getsize(path)))


if __name__ == "__main__":
    main()
