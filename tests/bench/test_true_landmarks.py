"""bench/accuracy/true_landmarks.py, the true landmark pairs of a benchmark pair: each written
row of the target table is g of the same row of the source table, the selections keep what they
say (moving vertices, a box, every N-th), and bad input is refused with a message."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy", "true_landmarks.py")


def make_pair(tmp_path):
    """A 2D pair: a circle of 100 points, g shifts its upper half (y > 0) by (0.1 * y, 0)."""
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    src = np.c_[np.cos(t), np.sin(t)]
    tru = src.copy()
    tru[:, 0] += 0.1 * np.maximum(src[:, 1], 0)
    d = tmp_path / "pair"
    d.mkdir()
    (d / "pair.json").write_text(json.dumps({"dimension": 2}))
    with open(d / "source.polyline", "w") as f:
        f.write("# a circle\n")
        for p in src:
            f.write("%.7f %.7f\n" % tuple(p))
    np.savetxt(d / "truth.xyz", np.c_[tru, np.zeros(len(tru))], fmt="%.7f")
    return d, src, tru


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *map(str, args)], capture_output=True, text=True)


def read(path):
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_rows_are_source_vertices_and_their_images(tmp_path):
    d, src, tru = make_pair(tmp_path)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    r = run(d, "--out-source", a, "--out-target", b, "--every", 1)
    assert r.returncode == 0, r.stderr
    assert "100 pairs" in r.stdout
    assert open(a).readline().strip() == "x,y"
    np.testing.assert_allclose(read(a), src, atol=1e-6)
    np.testing.assert_allclose(read(b), tru, atol=1e-6)


def test_selections(tmp_path):
    d, src, tru = make_pair(tmp_path)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    # Moving: only the upper half moves, and more than half its largest motion where y > 0.5.
    assert run(d, "--out-source", a, "--out-target", b, "--every", 1, "--moving", 0.5).returncode == 0
    pa = read(a)
    assert len(pa) == np.sum(src[:, 1] > 0.5) and np.all(pa[:, 1] > 0.5)
    # A box (given as --box=..., its first number negative), every 3rd.
    assert run(d, "--out-source", a, "--out-target", b, "--every", 3, "--box=-2,0,-2,0").returncode == 0
    inside = np.where((src[:, 0] <= 0) & (src[:, 1] <= 0))[0][::3]
    np.testing.assert_allclose(read(a), src[inside], atol=1e-6)
    np.testing.assert_allclose(read(b), tru[inside], atol=1e-6)


@pytest.mark.parametrize("extra, message", [
    (["--every", "0"], "--every"),
    (["--box=0,1"], "--box takes 4"),
    (["--moving", "2"], "keeps no vertex"),
])
def test_bad_input_is_refused(tmp_path, extra, message):
    d, _, _ = make_pair(tmp_path)
    r = run(d, "--out-source", tmp_path / "a.csv", "--out-target", tmp_path / "b.csv", *extra)
    assert r.returncode == 1 and message in r.stderr


def test_missing_pair(tmp_path):
    r = run(tmp_path / "none", "--out-source", tmp_path / "a.csv", "--out-target", tmp_path / "b.csv")
    assert r.returncode == 1 and "cannot read the pair" in r.stderr
