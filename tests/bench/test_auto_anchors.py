"""Automatic landmarks and anchors (docs/numerics.md "Automatic landmarks", "Automatic anchors")
on benchmark pairs with a known map (bench/accuracy/make_pairs.py), levels 4..7 (a few seconds):
- the figure's arms raised to horizontal: the arms swing far, the landmarks act and the figure's
  body, which the true map keeps still, coincides in both shapes; the anchors must hold it: the
  error on the vertices g keeps still falls several-fold, and the error over all vertices too;
- the figure's legs spread 25 degrees: the feet move by just under sigma of level 4, the old
  threshold of the landmarks (--auto-landmark-min-motion 1); without them the legs are reached
  only by the second path and with twice the error, with them (by default, on every pair) the
  first path reaches them;
- the arms raised to horizontal again, with the pair's true landmarks given (--landmarks: the
  head, the hands, a foot and a point of the crotch, with their images under g): the anchors act beside them (--landmark-anchors on, the default), and the body
  stays; with --landmark-anchors off (the behaviour before 2026-11-29) given landmarks turned
  the anchors off and the body slid."""

import json

import numpy as np
import pytest

from bench_pairs import generate_and_match  # tests/bench/bench_pairs.py (puts bench/accuracy on sys.path)
from score import read_points  # noqa: E402  (bench/accuracy/score.py)

PAIR = "figure_arms_horizontal"
LEGS = "figure_legs_spread"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return generate_and_match(tmp_path_factory.mktemp("anchors"), PAIR,
                              {"on": ["--auto-anchors", "on", "--inner-distance-weight", "0"],
                               "off": ["--auto-anchors", "off", "--inner-distance-weight", "0"]})


@pytest.fixture(scope="module")
def legs(tmp_path_factory):
    return generate_and_match(tmp_path_factory.mktemp("legs"), LEGS,
                              {"default": [], "threshold": ["--auto-landmark-min-motion", "1"]})


@pytest.fixture(scope="module")
def given(tmp_path_factory):
    root = tmp_path_factory.mktemp("given")
    marks = ["--landmarks", str(root / "pairs" / PAIR / "landmarks_source.csv"),
             str(root / "pairs" / PAIR / "landmarks_target.csv")]
    # Without the rigid limbs, which act with the anchors and would be measured with them here
    # (tests/bench/test_rigid_limbs.py): they carry the arms whole and leave the skin under the
    # armpits to slide, so the still vertices' error rises while the whole error falls.
    off = ["--rigid-limb-weight", "0"]
    return generate_and_match(root, PAIR, {"on": marks + off + ["--landmark-anchors", "on"],
                                           "off": marks + off + ["--landmark-anchors", "off"]})


def errors(pair, run):
    """|phi(v) - g(v)| over the source's vertices and the mask of those g keeps still, unit box."""
    report = json.load(open(run / "report.json"))
    scale = report["placement"]["scale"]
    v, g, phi = (read_points(str(p), 2) for p in
                 (pair / "source.polyline", pair / "truth.xyz", run / "deformed.obj"))
    assert len(v) == len(g) == len(phi)
    still = np.linalg.norm(g - v, axis=1) * scale < 5e-3
    return np.linalg.norm(phi - g, axis=1) * scale, still, report


def test_anchors_hold_what_the_motion_left_in_place(runs):
    pair, run = runs
    e_on, still, on = errors(pair, run["on"])
    e_off, _, off = errors(pair, run["off"])
    assert on["autoLandmarks"]["used"] and off["autoLandmarks"]["used"]
    assert 0 < on["autoLandmarks"]["anchors"] <= 100 and off["autoLandmarks"]["anchors"] == 0
    assert 0.3 < still.mean() < 0.9  # the body and legs stay, the arms move
    # Measured: on the still vertices 33.6e-3 without, 4.4e-3 with; over all 32.5e-3 and 14.7e-3.
    assert e_on[still].mean() < 0.3 * e_off[still].mean(), (e_on[still].mean(), e_off[still].mean())
    assert e_on.mean() < 0.6 * e_off.mean(), (e_on.mean(), e_off.mean())
    # Still a fit: positive Jacobians, residual below half the finest cell.
    for r in (on, off):
        assert r["result"]["minJacobian"] > 0
        assert r["result"]["residual"]["meanUnit"] < 0.5 * 2.0 ** -7


def test_landmarks_on_every_pair_reach_the_spread_legs(legs):
    pair, run = legs
    e_new, _, new = errors(pair, run["default"])
    e_old, _, old = errors(pair, run["threshold"])
    motion = np.linalg.norm(read_points(str(pair / "truth.xyz"), 2)
                            - read_points(str(pair / "source.polyline"), 2), axis=1).mean()
    motion *= new["placement"]["scale"]
    # The feet move by just under sigma of level 4 (0.125): the threshold of 1 sigma keeps the
    # landmarks out, the default (0) lets them act, and the anchors with them (the head stays).
    assert 0.1 < new["autoLandmarks"]["maxMotion"] < 0.125, new["autoLandmarks"]
    assert not old["autoLandmarks"]["used"] and new["autoLandmarks"]["used"]
    assert new["autoLandmarks"]["anchors"] > 0
    # Measured (2D metric weight 2 sigma^2): 25.0e-3 (0.63x the motion) without, 12.9e-3 (0.33x)
    # with. Without them the first path leaves the feet behind (2.4% of M1 farther than sigma)
    # and only the second path reaches them; with them the first path does.
    assert e_old.mean() > 0.5 * motion, (e_old.mean(), motion)
    assert e_new.mean() < 0.4 * motion, (e_new.mean(), motion)
    assert e_new.mean() < 0.6 * e_old.mean(), (e_new.mean(), e_old.mean())
    assert old["secondPath"]["ran"] and not new["secondPath"]["ran"], (old["secondPath"],
                                                                        new["secondPath"])
    assert new["result"]["residual"]["meanUnit"] < 0.5 * 2.0 ** -7
    assert new["result"]["minJacobian"] > 0


def test_anchors_act_beside_given_landmarks(given):
    pair, run = given
    e_on, still, on = errors(pair, run["on"])
    e_off, _, off = errors(pair, run["off"])
    assert on["landmarks"]["count"] == off["landmarks"]["count"] == 5
    assert on["parameters"]["landmarkAnchors"] == "on"
    assert off["parameters"]["landmarkAnchors"] == "off"
    # The extremities only decide the anchors and feed the inner-distance term: they are not
    # landmarks.
    a = on["autoLandmarks"]
    assert not a["used"] and "given landmarks" in a["reason"] and len(a["pairs"]) == 5, a
    assert on["innerDistance"]["used"] and not off["innerDistance"]["used"]
    assert 0 < a["anchors"] <= 100, a
    assert "autoLandmarks" not in off
    # Measured: on the still vertices 20.1e-3 without the anchors, 2.29e-3 with (and the
    # inner-distance term); over all 22.1e-3 and 9.31e-3 (without any landmarks: 12.8e-3).
    assert e_on[still].mean() < 0.3 * e_off[still].mean(), (e_on[still].mean(), e_off[still].mean())
    assert e_on.mean() < 0.7 * e_off.mean(), (e_on.mean(), e_off.mean())
    for r in (on, off):
        assert r["result"]["minJacobian"] > 0
        assert r["result"]["residual"]["meanUnit"] < 0.5 * 2.0 ** -7
