"""bench/accuracy/inner_distance.py, the measure of whether a 2D match keeps the inner distance to
the nearest limb end (docs/results.md, "The inner distance to the nearest extremity"): a rigid
motion keeps it, a slide of the skin along the limb changes it by the slide, the oracle undoes the
slide, the distance to each point's own end (--ratio) leaves out the middle of the limb, and bad
input is refused with exit status 2."""

import json
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import inner_distance as idist  # noqa: E402

LENGTH, WIDTH, STEP = 1.0, 0.1, 0.01


def limb():
    """A LENGTH x WIDTH rectangle (a limb), counter-clockwise, one point every STEP."""
    t = np.arange(0, LENGTH, STEP)
    s = np.arange(0, WIDTH, STEP)
    return np.vstack([np.c_[t, 0 * t], np.c_[LENGTH + 0 * s, s], np.c_[LENGTH - t, WIDTH + 0 * t],
                      np.c_[0 * s, WIDTH - s]])


def rigid(p, degrees=30.0, shift=(0.3, 0.2)):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return np.asarray(p) @ np.array([[c, -s], [s, c]]).T + shift


def write_polyline(path, pts):
    np.savetxt(path, pts, header="polyline")


def write_case(tmp_path, slide=0.0):
    """A pair whose g is rigid, and a run whose phi is g after sliding the long sides' vertices
    (between 0.1 and 0.4 of its length) by `slide` toward the middle: phi(M1) stays on M2."""
    pair = tmp_path / "pair"
    pair.mkdir(exist_ok=True)
    src = limb()
    truth = rigid(src)
    json.dump({"name": "limb", "dimension": 2}, open(pair / "pair.json", "w"))
    write_polyline(pair / "source.polyline", src)
    write_polyline(pair / "target_resampled.polyline", truth[::2])
    np.savetxt(pair / "truth.xyz", truth)
    slid = src.copy()
    side = ((src[:, 1] == 0) | (src[:, 1] == WIDTH)) & (src[:, 0] > 0.1) & (src[:, 0] < 0.4)
    slid[side, 0] += slide
    run = tmp_path / ("run%g" % slide)
    run.mkdir(exist_ok=True)
    ends = [[0.05, 0.05], [0.95, 0.05]]
    json.dump({"placement": {"scale": 1.0},
               "autoLandmarks": {"pairs": [{"source": e + [0.0],
                                            "target": list(rigid(e)) + [0.0]} for e in ends]}},
              open(run / "report.json", "w"))
    with open(run / "deformed.obj", "w") as f:
        for p in rigid(slid):
            f.write("v %.17g %.17g 0\n" % (p[0], p[1]))
    return str(pair), str(run), side


def parse(line):
    tok = line.split()
    out = {"label": tok[0], "pair": tok[1]}
    i = 2
    while i < len(tok):
        if tok[i] in ("moving", "all"):
            out[tok[i] + " g"], out[tok[i] + " phi"] = float(tok[i + 2]), float(tok[i + 4])
            i += 5
        elif tok[i].startswith("own@"):
            out[tok[i]] = {"share": float(tok[i + 2]), "g": float(tok[i + 4]),
                           "phi": float(tok[i + 6])}
            i += 7
        else:
            out[tok[i]] = float(tok[i + 1])
            i += 2
    return out


def test_rigid_motion_keeps_the_inner_distance_and_a_slide_does_not(tmp_path, capsys):
    pair, exact, _ = write_case(tmp_path, 0.0)
    _, slid, side = write_case(tmp_path, 0.05)
    idist.main(["--pair", pair, "--run", "exact=" + exact, "--run", "slid=" + slid,
                "--radius", "60"])
    a, b = [parse(x) for x in capsys.readouterr().out.strip().split("\n")]
    # units: 10^-3 of the box, scale 1. A rigid g keeps F up to the pixel graph's error.
    assert a["err"] == pytest.approx(0.0, abs=1e-9)
    assert a["all g"] == a["all phi"] and a["all g"] < 4.0
    # The slide moves 28% of the vertices by 50 toward the middle (F grows monotonically there).
    assert b["err"] == pytest.approx(50.0 * side.mean(), rel=1e-3)
    assert b["all phi"] > 0.8 * b["err"] and b["all phi"] > 4 * b["all g"]
    # The oracle picks, among the points of M2 within 60 of phi(v), the one keeping F: on the slid
    # vertices that is g(v), within the pixel graph's error. (Elsewhere F's level sets meet the
    # outline twice within 60, at the ends: the mean over all vertices falls less.)
    assert b["oracle@60"] < 0.6 * b["err"]
    src = limb()
    truth = rigid(src)
    ends = [[0.05, 0.05], [0.95, 0.05]]
    lo, hi = np.array([-0.5, -0.5]), np.array([1.5, 1.5])
    f1 = idist.InnerDistance([src], ends, lo, hi, 0.004)
    f2 = idist.InnerDistance([truth[::2]], [rigid(e) for e in ends], lo, hi, 0.004)
    slid = src.copy()
    slid[side, 0] += 0.05
    candidates = idist.edge_points([truth[::2]])
    picked = idist.oracle(rigid(slid)[side], f1(src)[side], candidates, f2(candidates), 0.06)
    # (M2's candidates lie 0.005 apart: within two of them, a fifth of the slide)
    assert np.linalg.norm(picked - truth[side], axis=1).mean() < 0.01


def test_own_extremity_leaves_out_the_middle_of_the_limb(tmp_path, capsys):
    pair, exact, _ = write_case(tmp_path, 0.0)
    _, slid, side = write_case(tmp_path, 0.05)
    idist.main(["--pair", pair, "--run", "exact=" + exact, "--run", "slid=" + slid,
                "--ratio", "1", "--ratio", "1.5"])
    a, b = [parse(x) for x in capsys.readouterr().out.strip().split("\n")]
    # Ratio 1 keeps every vertex; 1.5 leaves out the long sides' middle, where the two ends are
    # about as far: x in (0.41, 0.59) of the 2.2 of outline, about 16% of the vertices.
    assert a["own@1"]["share"] == 100 and b["own@1"]["share"] == 100
    assert 78 < a["own@1.5"]["share"] < 90, a
    # A rigid g keeps each point's distance to its own end, as it keeps the distance to the
    # nearest; the slide (0.1 < x < 0.4, kept at 1.5) changes it by the slide on the slid
    # vertices, so the kept mean is at least the slide times their share among the kept.
    for r in ("own@1", "own@1.5"):
        assert a[r]["g"] == a[r]["phi"] < 4.0, a
    kept = 0.01 * b["own@1.5"]["share"]
    assert b["own@1.5"]["phi"] > 0.8 * 50.0 * side.mean() / kept, b
    assert b["own@1.5"]["phi"] > 4 * b["own@1.5"]["g"], b
    with pytest.raises(SystemExit) as e:
        idist.main(["--pair", pair, "--run", "x=" + exact, "--ratio", "0.5"])
    assert e.value.code == 2


def test_bad_input_exits_2(tmp_path, capsys):
    pair, run, _ = write_case(tmp_path, 0.0)
    with pytest.raises(SystemExit) as e:
        idist.main(["--pair", pair, "--run", "no-label-separator"])
    assert e.value.code == 2
    report = json.load(open(os.path.join(run, "report.json")))
    del report["autoLandmarks"]
    json.dump(report, open(os.path.join(run, "report.json"), "w"))
    with pytest.raises(SystemExit) as e:
        idist.main(["--pair", pair, "--run", "x=" + run])
    assert e.value.code == 2
    assert "no paired extremities" in capsys.readouterr().err
    json.dump({"name": "c", "dimension": 3}, open(os.path.join(pair, "pair.json"), "w"))
    with pytest.raises(SystemExit) as e:
        idist.main(["--pair", pair, "--run", "x=" + run])
    assert e.value.code == 2


def test_the_distance_runs_inside_the_shape():
    # A U: the square [0, 1]^2 less the slot [0.4, 0.6] x [0.2, 1]. From the top of one arm to the
    # top of the other the path runs down to the slot's corner, across its bottom and up:
    # 2 * sqrt(0.7^2 + 0.2^2) + 0.2 = 1.656, against 0.6 straight across. The pixel graph's path
    # is a little longer (16 neighbours, and the inner pixels stay off the corners).
    u = np.array([[0, 0], [1, 0], [1, 1], [0.6, 1], [0.6, 0.2], [0.4, 0.2], [0.4, 1], [0, 1]])
    f = idist.InnerDistance([u], [[0.2, 0.9]], [-0.1, -0.1], [1.1, 1.1], 0.005)
    near, far = f([[0.2, 0.8], [0.8, 0.9]])
    assert near == pytest.approx(0.1, abs=0.005)
    assert 1.656 < far < 1.72
