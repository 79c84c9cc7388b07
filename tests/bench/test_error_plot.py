"""bench/accuracy/error_plot.py, the picture of where a 2D match slides along M2
(docs/results.md, "Where the 2D large-motion error sits"): the error per run against the known
map in units of 10^-3 of the box, one pair or one per run, and bad input refused with exit
status 2."""

import json
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import error_plot as ep  # noqa: E402


def square(n, side=1.0):
    """n points per side of a square, counter-clockwise."""
    t = np.linspace(0, side, n, endpoint=False)
    z = np.zeros(n)
    return np.vstack([np.c_[t, z], np.c_[z + side, t], np.c_[side - t, z + side],
                      np.c_[z, side - t]])


def write_pair(d, dim=2, name="sq", motion=0.5):
    os.makedirs(d, exist_ok=True)
    src = square(5)
    truth = src + [0.5, 0.0]  # g moves every vertex by 0.5
    json.dump({"name": name, "dimension": dim, "motion": {"meanWorld": motion}},
              open(os.path.join(d, "pair.json"), "w"))
    np.savetxt(os.path.join(d, "truth.xyz"), truth)
    np.savetxt(os.path.join(d, "target_resampled.polyline"), truth[::2])
    return truth


def write_run(d, phi, scale=2.0):
    os.makedirs(d, exist_ok=True)
    json.dump({"placement": {"scale": scale}}, open(os.path.join(d, "report.json"), "w"))
    with open(os.path.join(d, "deformed.obj"), "w") as f:
        for p in phi:
            f.write("v %.17g %.17g 0\n" % (p[0], p[1]))


def test_errors_in_box_units_and_picture(tmp_path, capsys):
    truth = write_pair(str(tmp_path / "pair"))
    exact, off = str(tmp_path / "exact"), str(tmp_path / "off")
    write_run(exact, truth)
    moved = truth.copy()
    moved[::2] += [0.0, 0.01]  # half the vertices 0.01 world units off: mean 0.005
    write_run(off, moved)
    out = str(tmp_path / "e.png")
    ep.main(["--pair", str(tmp_path / "pair"), "--run", "a=" + exact, "--run", "b=" + off,
             "-o", out, "--every", "3"])
    lines = capsys.readouterr().out.split("\n")
    # world 0.005 x scale 2 = 0.01 of the box = 10 x 1e-3; motion 0.5 x 2 x 1e3 = 1000.
    assert lines[0] == "a sq err 0 motion 1000 ratio 0.000"
    assert lines[1] == "b sq err 10 motion 1000 ratio 0.010"
    assert lines[2] == out
    with open(out, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_one_pair_per_run(tmp_path, capsys):
    t1 = write_pair(str(tmp_path / "p1"), name="one")
    t2 = write_pair(str(tmp_path / "p2"), name="two", motion=1.0)
    write_run(str(tmp_path / "r1"), t1)
    write_run(str(tmp_path / "r2"), t2 + [0.0, 0.002], scale=1.0)
    ep.main(["--pair", str(tmp_path / "p1"), "--pair", str(tmp_path / "p2"),
             "--run", "x=" + str(tmp_path / "r1"), "--run", "y=" + str(tmp_path / "r2"),
             "-o", str(tmp_path / "e.png"), "--columns", "1"])
    lines = capsys.readouterr().out.split("\n")
    assert lines[0].startswith("x one err 0 ")
    assert lines[1] == "y two err 2 motion 1000 ratio 0.002"


@pytest.mark.parametrize("case", ["3d", "count", "spec", "pairs", "every", "missing"])
def test_bad_input_exits_2(tmp_path, case, capsys):
    truth = write_pair(str(tmp_path / "pair"), dim=3 if case == "3d" else 2)
    run = str(tmp_path / "run")
    write_run(run, truth[:-1] if case == "count" else truth)
    args = ["--pair", str(tmp_path / "pair"), "--run", "a=" + run, "-o", str(tmp_path / "e.png")]
    if case == "spec":
        args[3] = run
    elif case == "pairs":
        args += ["--pair", str(tmp_path / "pair"), "--pair", str(tmp_path / "pair")]
    elif case == "every":
        args += ["--every", "0"]
    elif case == "missing":
        args[3] = "a=" + str(tmp_path / "nowhere")
    with pytest.raises(SystemExit) as e:
        ep.main(args)
    assert e.value.code == 2
    assert "error_plot.py: " in capsys.readouterr().err
    assert not os.path.exists(str(tmp_path / "e.png"))
