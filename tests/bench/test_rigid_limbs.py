"""Rigid limbs (docs/numerics.md "Rigid limbs") on the benchmark's swung leg
(bench/accuracy/make_pairs.py animal_leg_swing: the front right leg swung 90 degrees forward at
the shoulder), levels 4..6 (a few seconds each):
- the leg is found rigid, with about g's 90 degrees, and its 20 points are held at every level;
  the anchors are sought again with the smaller radius;
- the leg no longer turns about its own axis on the way (bench/accuracy/limb_twist.py: every
  slab's median turn within 15 degrees, against 20-30 with --rigid-limb-weight 0, the default
  before 2026-12-02), and the error over all vertices falls by more than a fifth;
- in 2D (the default since 2026-12-02's twenty-second session), the figure's arms raised to
  horizontal (figure_arms_horizontal, levels 4..7): both arms are found rigid with about g's 90
  degrees (from the fit's twelve starts: from the principal axes alone it ended at 116 and was
  left out), the anchors keep their radius, the arms' vertices (those g moves by more than 0.3
  of its largest motion) come within a tenth of their error without the limbs, and the error
  over all vertices falls by half;
- rigid segments (docs/numerics.md "Rigid segments", 2D, since 2026-12-02's twenty-fifth
  session): on the squat (figure_knees_bent, levels 4..7), whose feet stay, both thighs are
  held as segments with about g's 22 degrees, the thighs' error falls below half of that with
  --rigid-segment off, and the error over all vertices by more than a third."""

import json

import numpy as np
import pytest

from bench_pairs import generate_and_match  # tests/bench/bench_pairs.py (puts bench/accuracy on sys.path)
from score import read_points  # noqa: E402  (bench/accuracy/score.py)
from limb_twist import twist_table  # noqa: E402  (bench/accuracy/limb_twist.py)

PAIR = "animal_leg_swing"
ARMS = "figure_arms_horizontal"
SQUAT = "figure_knees_bent"
LIMBS = {"on": [], "off": ["--rigid-limb-weight", "0"]}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return generate_and_match(tmp_path_factory.mktemp("limbs"), PAIR, LIMBS, "4..6", threads=2)


@pytest.fixture(scope="module")
def arms(tmp_path_factory):
    return generate_and_match(tmp_path_factory.mktemp("arms"), ARMS, LIMBS, "4..7", threads=2)


@pytest.fixture(scope="module")
def squat(tmp_path_factory):
    return generate_and_match(tmp_path_factory.mktemp("squat"), SQUAT,
                              {"on": [], "off": ["--rigid-segment", "off"]}, "4..7", threads=2)


def measured(pair, run):
    """(mean |phi(v) - g(v)| over the source's vertices, the leg's slabs' median turns)."""
    v, g, phi = (read_points(str(p), 3) for p in
                 (pair / "source.obj", pair / "truth.xyz", run / "deformed.obj"))
    assert len(v) == len(g) == len(phi)
    turns = [row[2] for row in twist_table(v, g, phi, 0.3, 4)]
    return float(np.linalg.norm(phi - g, axis=1).mean()), turns


def test_the_leg_is_held_rigid(runs):
    _, run = runs
    on = json.load(open(run["on"] / "report.json"))
    off = json.load(open(run["off"] / "report.json"))
    limbs = on["autoLandmarks"]["rigidLimbs"]
    used = [l for l in limbs if l["used"]]
    assert len(used) == 1, limbs
    assert 80 < used[0]["angleDegrees"] < 100, used[0]
    assert used[0]["residual"] < 0.003, used[0]
    assert on["autoLandmarks"]["rigidLimbPoints"] == 20
    assert on["autoLandmarks"]["anchorRadius"] == 0.015
    assert on["parameters"]["rigidLimbWeight"] == 1e4
    assert "rigidLimbs" not in off["autoLandmarks"], off["autoLandmarks"].keys()
    assert off["autoLandmarks"]["anchorRadius"] == 0.03


def test_the_leg_does_not_turn_about_its_axis(runs):
    pair, run = runs
    err_on, turns_on = measured(pair, run["on"])
    err_off, turns_off = measured(pair, run["off"])
    assert max(abs(t) for t in turns_on) < 15, turns_on
    assert min(abs(t) for t in turns_off) > 20, turns_off
    assert err_on < 0.8 * err_off, (err_on, err_off)



def test_the_raised_arms_are_carried_whole_in_2d(arms):
    pair, run = arms
    on = json.load(open(run["on"] / "report.json"))
    used = [l for l in on["autoLandmarks"]["rigidLimbs"] if l["used"]]
    assert len(used) == 2, on["autoLandmarks"]["rigidLimbs"]
    for limb in used:
        assert 85 < limb["angleDegrees"] < 95 and limb["residual"] < 0.002, limb
    assert on["autoLandmarks"]["rigidLimbPoints"] == 40
    assert on["autoLandmarks"]["anchorRadius"] == 0.03  # the nearer anchors are 3D only
    v, g = (read_points(str(p), 2) for p in (pair / "source.polyline", pair / "truth.xyz"))
    motion = np.linalg.norm(g - v, axis=1)
    arm = motion > 0.3 * motion.max()
    err = {}
    for label in ("on", "off"):
        phi = read_points(str(run[label] / "deformed.obj"), 2)
        err[label] = np.linalg.norm(phi - g, axis=1)
    assert err["on"][arm].mean() < 0.1 * err["off"][arm].mean(), (err["on"][arm].mean(),
                                                                  err["off"][arm].mean())
    assert err["on"].mean() < 0.5 * err["off"].mean(), (err["on"].mean(), err["off"].mean())


def test_the_squats_thighs_are_held_as_segments_in_2d(squat):
    pair, run = squat
    on = json.load(open(run["on"] / "report.json"))
    off = json.load(open(run["off"] / "report.json"))
    limbs = on["autoLandmarks"]["rigidLimbs"]
    used = [l for l in limbs if l["used"]]
    assert len(used) == 2 and all(l["segment"] for l in used), limbs
    for limb in used:
        assert 17 < limb["angleDegrees"] < 28 and limb["residual"] < 0.003, limb
    assert on["autoLandmarks"]["rigidLimbPoints"] == 40
    assert on["parameters"]["rigidSegment"] == "0.55,0.8"
    assert "rigidLimbs" not in off["autoLandmarks"], off["autoLandmarks"].keys()
    v, g = (read_points(str(p), 2) for p in (pair / "source.polyline", pair / "truth.xyz"))
    thighs = (np.abs(v[:, 0]) < 0.25) & (v[:, 1] > -0.45) & (v[:, 1] < -0.15)
    err = {}
    for label in ("on", "off"):
        phi = read_points(str(run[label] / "deformed.obj"), 2)
        err[label] = np.linalg.norm(phi - g, axis=1)
    assert err["on"][thighs].mean() < 0.5 * err["off"][thighs].mean(), (
        err["on"][thighs].mean(), err["off"][thighs].mean())
    assert err["on"].mean() < 0.67 * err["off"].mean(), (err["on"].mean(), err["off"].mean())
