"""bench/accuracy/segment_fit.py, the prototype of a rigid segment fitted between two joints:
on a shape moved rigidly and sampled anew it finds the motion (angle and images), and it refuses
bad input with a message."""

import os
import subprocess
import sys

import numpy as np

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy", "segment_fit.py")


def ellipse(n, phase, degrees, centre=(3.0, 0.5)):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False) + phase
    p = np.c_[np.cos(t), 0.4 * np.sin(t)]
    a = np.radians(degrees)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return p @ rot.T + np.asarray(centre), rot


def write(path, pts):
    with open(path, "w") as f:
        f.write("# test curve\n")
        for p in pts:
            f.write("%.9f %.9f\n" % tuple(p))


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *map(str, args)], capture_output=True, text=True)


def test_finds_a_rigid_motion_of_a_resampled_shape(tmp_path):
    src, _ = ellipse(400, 0.0, 0.0)
    tgt, rot = ellipse(370, 0.01, 25.0)  # sampled anew: other count, other phase
    write(tmp_path / "a.polyline", src)
    write(tmp_path / "b.polyline", tgt)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    r = run(tmp_path / "a.polyline", tmp_path / "b.polyline", "--lo", 0, "--hi", 100,
            "--sides", "+1", "--every", 10, "--out-source", a, "--out-target", b)
    assert r.returncode == 0, r.stderr
    angle = float(r.stdout.split("angle ")[1].split()[0])
    assert abs(angle - 25.0) < 0.5
    pa = np.loadtxt(a, delimiter=",", skiprows=1)
    pb = np.loadtxt(b, delimiter=",", skiprows=1)
    assert len(pa) == 40
    truth = (pa - [3.0, 0.5]) @ rot.T + [3.0, 0.5]
    assert np.abs(pb - truth).max() < 0.02


def test_bad_input_is_refused(tmp_path):
    src, _ = ellipse(100, 0.0, 0.0)
    write(tmp_path / "a.polyline", src)
    base = [tmp_path / "a.polyline", tmp_path / "a.polyline", "--out-source", tmp_path / "x.csv",
            "--out-target", tmp_path / "y.csv"]
    r = run(*base, "--lo", 1, "--hi", 0.5)
    assert r.returncode == 1 and "--lo < --hi" in r.stderr
    r = run(*base, "--lo", 0, "--hi", 1, "--sides", "-1")
    assert r.returncode == 1 and "no vertex with x of sign -1" in r.stderr
    r = run(*base, "--lo", 50, "--hi", 60, "--sides", "+1")
    assert r.returncode == 1 and "the segment has 0 and 0 vertices" in r.stderr
    r = run(tmp_path / "none.polyline", *base[1:], "--lo", 0, "--hi", 1)
    assert r.returncode == 1 and "segment_fit.py:" in r.stderr
    (tmp_path / "empty.polyline").write_text("# no points\n")
    r = run(tmp_path / "empty.polyline", *base[1:], "--lo", 0, "--hi", 1)
    assert r.returncode == 1 and "not a closed polyline of at least 3 points" in r.stderr


def test_chords_measure_a_noisy_outline_as_its_shape(tmp_path):
    """--hop 3 measures s over chords: on a noisy copy of the ellipse the same band then holds
    about as many vertices as on the clean one, while the arc length (--hop 1) shrinks it."""
    src, _ = ellipse(400, 0.0, 0.0)
    rng = np.random.default_rng(1)
    noisy = src + rng.normal(0.0, 0.004, src.shape)
    write(tmp_path / "a.polyline", src)
    write(tmp_path / "b.polyline", noisy)
    counts = {}
    for hop in (1, 3):
        r = run(tmp_path / "a.polyline", tmp_path / "b.polyline", "--lo", 0.5, "--hi", 1.5,
                "--sides", "+1", "--hop", hop, "--out-source", tmp_path / "x.csv",
                "--out-target", tmp_path / "y.csv")
        assert r.returncode == 0, r.stderr
        n1, n2 = (int(v) for v in r.stdout.split(": ")[1].split(" vertices")[0].split(" and "))
        counts[hop] = (n1, n2)
    clean = counts[3][0]
    assert abs(counts[3][1] - clean) < abs(counts[1][1] - clean)
    assert abs(counts[3][1] - clean) <= 0.1 * clean
