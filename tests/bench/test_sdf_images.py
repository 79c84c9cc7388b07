"""bench/accuracy/sdf_images.py, the signed-distance images the image-registration peer (ANTs
SyN, bench/compare_peers.sh --syn) registers: exact distances near the shapes, the sign, the
placement of vdb_match, and the source points in that placement."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy", "sdf_images.py")


def run(pair, out, level, *extra):
    subprocess.run([sys.executable, SCRIPT, "--pair", str(pair), "--level", str(level), "--out",
                    str(out), *extra], check=True)


def read_mhd(path):
    header = dict(line.split(" = ", 1) for line in open(path).read().splitlines())
    dim = int(header["NDims"])
    n = [int(x) for x in header["DimSize"].split()]
    raw = os.path.join(os.path.dirname(path), header["ElementDataFile"])
    a = np.fromfile(raw, np.float32).reshape(tuple(reversed(n)))
    h = float(header["ElementSpacing"].split()[0])
    return a.transpose(*reversed(range(dim))), h  # a[i, j(, k)] at (i, j(, k)) h


def write_circle(path, centre, radius, n):
    t = 2 * np.pi * np.arange(n) / n
    pts = np.stack([centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)], axis=1)
    np.savetxt(path, pts, fmt="%.12g")
    return pts


def test_2d_distances_sign_and_placement(tmp_path):
    pair = tmp_path / "pair"
    pair.mkdir()
    (pair / "pair.json").write_text(json.dumps({"dimension": 2}))
    n = 400
    src = write_circle(pair / "source.polyline", (1.0, 2.0), 0.4, n)
    write_circle(pair / "target_resampled.polyline", (1.2, 2.0), 0.3, 300)
    run(pair, tmp_path / "out", 6)

    place = json.load(open(tmp_path / "out" / "placement.json"))
    # vdb_match's placement: the union of the vertex boxes, largest side 0.6, centred
    lo = np.minimum(src.min(axis=0), [0.9, 1.7])
    hi = np.maximum(src.max(axis=0), [1.5, 2.3])
    scale = 0.6 / (hi - lo).max()
    assert place["scale"] == pytest.approx(scale, rel=1e-9)
    assert scale * ((lo + hi) / 2 - np.array(place["origin"])) == pytest.approx([0.5, 0.5])

    a, h = read_mhd(str(tmp_path / "out" / "source_sdf.mhd"))
    assert a.shape == (65, 65) and h == 2.0 ** -6
    ii, jj = np.meshgrid(np.arange(65), np.arange(65), indexing="ij")
    world = np.stack([ii, jj], axis=-1) * h / scale + np.array(place["origin"])
    exact = np.linalg.norm(world - [1.0, 2.0], axis=-1) - 0.4  # world units
    chord = 0.4 * (1 - np.cos(np.pi / n))  # the polygon lies inside the circle by at most this
    near = np.abs(exact) * scale < 0.3
    assert np.abs(a[near] - scale * exact[near]).max() <= scale * chord + 1e-6
    assert (a[exact * scale < -1e-3] < 0).all() and (a[exact * scale > 1e-3] > 0).all()
    assert a.max() == pytest.approx(0.3)  # clamped at the band

    unit = np.loadtxt(tmp_path / "out" / "source_points.csv", delimiter=",", skiprows=1)
    assert unit.shape == (n, 5)  # x, y, t, label, comment
    assert unit[:, :2] == pytest.approx(scale * (src - place["origin"]), abs=1e-9)


def test_target_option_reads_that_target(tmp_path):
    # --target target_scan (compare_peers.sh --scan): the target image is of that file, placed
    # with it: a circle of radius 0.25 instead of target_resampled's 0.3.
    pair = tmp_path / "pair"
    pair.mkdir()
    (pair / "pair.json").write_text(json.dumps({"dimension": 2}))
    write_circle(pair / "source.polyline", (1.0, 2.0), 0.4, 400)
    write_circle(pair / "target_resampled.polyline", (1.2, 2.0), 0.3, 300)
    write_circle(pair / "target_scan.polyline", (1.2, 2.0), 0.25, 300)
    for name, radius in (("target_resampled", 0.3), ("target_scan", 0.25)):
        out = tmp_path / name
        run(pair, out, 6, "--target", name)
        place = json.load(open(out / "placement.json"))
        a, h = read_mhd(str(out / "target_sdf.mhd"))
        centre = place["scale"] * (np.array([1.2, 2.0]) - np.array(place["origin"])) / h
        i, j = int(round(centre[0])), int(round(centre[1]))
        # At the node nearest the centre, the distance is minus the radius (unit-box lengths).
        off = np.linalg.norm((np.array([i, j]) - centre) * h)
        assert a[i, j] == pytest.approx(-place["scale"] * radius + off, abs=2e-3)


def test_3d_cube_distances(tmp_path):
    pytest.importorskip("pyopenvdb")
    pair = tmp_path / "pair"
    pair.mkdir()
    (pair / "pair.json").write_text(json.dumps({"dimension": 3}))
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]

    def write_cube(path, lo, side):
        with open(path, "w") as f:
            f.writelines("v %r %r %r\n" % tuple(lo + side * c) for c in corners)
            f.writelines("f %d %d %d %d\n" % q for q in quads)

    write_cube(pair / "source.obj", np.zeros(3), 1.0)
    write_cube(pair / "target_resampled.obj", np.array([0.1, 0.0, 0.0]), 0.9)
    run(pair, tmp_path / "out", 5)
    place = json.load(open(tmp_path / "out" / "placement.json"))
    scale, origin = place["scale"], np.array(place["origin"])
    assert scale == pytest.approx(0.6)

    a, h = read_mhd(str(tmp_path / "out" / "source_sdf.mhd"))
    assert a.shape == (33, 33, 33)
    idx = np.stack(np.meshgrid(*[np.arange(33)] * 3, indexing="ij"), axis=-1)
    p = idx * h / scale + origin  # world
    outside = np.linalg.norm(np.maximum(np.maximum(-p, p - 1), 0), axis=-1)
    inside = np.minimum(p, 1 - p).min(axis=-1)
    exact = scale * np.where(outside > 0, outside, -np.clip(inside, 0, None))
    near = np.abs(exact) < 3 * h  # OpenVDB's distances are exact in its narrow band
    assert near.sum() > 1000
    assert np.abs(a[near] - exact[near]).max() < 1e-3 * h
    b, _ = read_mhd(str(tmp_path / "out" / "target_sdf.mhd"))
    assert (b < 0).sum() < (a < 0).sum()  # the smaller cube


def test_sample_is_multilinear():
    sys.path.insert(0, os.path.dirname(SCRIPT))
    from sdf_images import sample

    h = 0.25
    ii = np.stack(np.meshgrid(*[np.arange(5)] * 3, indexing="ij"), axis=-1) * h
    a = 0.3 + 2.0 * ii[..., 0] - ii[..., 1] + 0.5 * ii[..., 2]  # linear: reproduced exactly
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 1, (200, 3))
    assert sample(a, h, p) == pytest.approx(0.3 + 2.0 * p[:, 0] - p[:, 1] + 0.5 * p[:, 2])
    nodes = rng.integers(0, 5, (50, 3))
    assert sample(a, h, nodes * h) == pytest.approx(a[tuple(nodes.T)])  # values at the nodes
    b = a[:, :, 0] * a[:, :, 0]  # 2D, bilinear: the cell centre is the mean of its corners
    assert sample(b, h, np.array([[0.125, 0.375]]))[0] == pytest.approx(b[0:2, 1:3].mean())


def test_transformix_points_round_trip(tmp_path):
    sys.path.insert(0, os.path.dirname(SCRIPT))
    from sdf_images import read_transformix_points, write_transformix_points

    for dim in (2, 3):
        p = np.random.default_rng(dim).uniform(0, 1, (7, dim))
        write_transformix_points(str(tmp_path / "in.txt"), p)
        lines = (tmp_path / "in.txt").read_text().splitlines()
        assert lines[:2] == ["point", "7"] and len(lines[2].split()) == dim
        # transformix -def writes one line per point; OutputPoint is the mapped one
        with open(tmp_path / "out.txt", "w") as f:
            for k, q in enumerate(p):
                c = " ".join(repr(float(x)) for x in q)
                f.write(f"Point\t{k}\t; InputIndex = [ 0 0 ]\t; InputPoint = [ {c} ]\t; "
                        f"OutputIndexFixed = [ 0 0 ]\t; OutputPoint = [ {' '.join(repr(float(x) + 1) for x in q)} ]"
                        f"\t; Deformation = [ 1 1 ]\n")
        assert read_transformix_points(str(tmp_path / "out.txt"), dim) == pytest.approx(p + 1)
