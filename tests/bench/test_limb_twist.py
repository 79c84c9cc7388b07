"""bench/accuracy/limb_twist.py, the measure of how far a map turns a swung limb about its own
axis: on a cylinder swung 90 degrees about a joint it reads 0 for g itself, a known torsion
slab by slab, a known constant turn, and nothing for a sideways shift of the limb."""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import limb_twist as lt  # noqa: E402


def rotation(axis, degrees):
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    t = np.radians(degrees)
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k


def swung_leg():
    """A body (a still slab of points) and a leg: a cylinder of radius 0.1 hanging from the
    joint at the origin along -z, length 1, sampled on rings. g swings the leg by 90 degrees
    about -y (forward, to +x) and keeps the body. Returns source, g(source) and the leg mask."""
    s = np.linspace(0.05, 1.0, 40)
    t = np.radians(np.arange(0, 360, 10))
    leg = np.array([[0.1 * np.cos(a), 0.1 * np.sin(a), -si] for si in s for a in t])
    body = np.array([[x, y, 0.3] for x in np.linspace(-1, 1, 21) for y in np.linspace(-1, 1, 21)])
    source = np.vstack([body, leg])
    mask = np.r_[np.zeros(len(body), bool), np.ones(len(leg), bool)]
    truth = source.copy()
    truth[mask] = source[mask] @ rotation((0, -1, 0), 90).T
    return source, truth, mask


def twist_about_leg(truth, mask, degrees_of):
    """truth with its leg turned about the swung leg's axis (+x through the origin) by
    degrees_of(distance along the axis)."""
    out = truth.copy()
    for i in np.nonzero(mask)[0]:
        p = truth[i]
        out[i] = rotation((1, 0, 0), degrees_of(p[0])) @ p
    return out


def test_g_itself_reads_no_twist():
    source, truth, _ = swung_leg()
    for _, _, med, mean, err in lt.twist_table(source, truth, truth.copy(), 0.3, 4):
        assert med == pytest.approx(0, abs=1e-9)
        assert mean == pytest.approx(0, abs=1e-9)
        assert err == pytest.approx(0, abs=1e-12)


def test_a_constant_turn_is_read_in_every_slab_with_its_sign():
    source, truth, mask = swung_leg()
    for degrees in (25.0, -40.0):
        phi = twist_about_leg(truth, mask, lambda x: degrees)
        rows = lt.twist_table(source, truth, phi, 0.3, 4)
        assert len(rows) == 4
        for _, _, med, mean, _ in rows:
            assert med == pytest.approx(degrees, abs=0.5)
            assert mean == pytest.approx(degrees, abs=0.5)


def test_a_torsion_is_read_slab_by_slab_from_the_joint_outwards():
    source, truth, mask = swung_leg()
    phi = twist_about_leg(truth, mask, lambda x: -60.0 * x)  # 0 at the joint, -60 at the foot
    rows = lt.twist_table(source, truth, phi, 0.3, 4)
    means = [r[3] for r in rows]
    assert all(b < a for a, b in zip(means, means[1:]))  # grows in magnitude outwards
    # The slabs split the moving part (g moves the leg's points by sqrt(2) times their
    # distance from the joint: more than 0.3 of the largest from x = 0.3 on) in equal counts.
    for (_, _, _, mean, _), lo, hi in zip(rows, (0.3, 0.475, 0.65, 0.825), (0.475, 0.65, 0.825, 1.0)):
        assert -60.0 * hi - 1.5 < mean < -60.0 * lo + 1.5


def test_a_sideways_shift_reads_no_twist():
    source, truth, mask = swung_leg()
    phi = truth.copy()
    phi[mask] += np.array([0.0, 0.03, -0.02])  # across the swung leg's axis (+x)
    for _, _, med, mean, err in lt.twist_table(source, truth, phi, 0.3, 4):
        # Each vertex's own angle reaches +-20 degrees (a shift of 0.36 radius); around the
        # ring they cancel but for the arctangent's curvature.
        assert abs(mean) < 1.0
        assert err == pytest.approx(np.hypot(0.03, 0.02), rel=1e-9)


def test_no_limb_is_refused():
    source, truth, _ = swung_leg()
    with pytest.raises(SystemExit):
        lt.twist_table(source, source.copy() + 1e-3 * (np.arange(len(source)) == 0)[:, None],
                       source, 0.3, 4)
