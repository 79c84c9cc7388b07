"""bench/accuracy/limb_sections.py, the diagnosis of how a map bends the creature's arms: on a
synthetic five-armed shape it finds the arms, measures a known along-arm stretch, and separates a
known turn of the arms' cross-sections (an along-arm shift linear in z) from the rest."""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import limb_sections as ls  # noqa: E402


def star():
    """Surface points and triangles of five box arms (reach 1, width and height 0.2) about the
    z-axis: each arm's top, bottom and two sides as triangulated grids."""
    pts, tris = [], []
    for k in range(5):
        a = np.radians(90 + 72 * k)
        u, w = np.array([np.cos(a), np.sin(a), 0.0]), np.array([-np.sin(a), np.cos(a), 0.0])
        z = np.array([0.0, 0.0, 1.0])
        s = np.linspace(0.0, 1.0, 41)
        t = np.linspace(-0.1, 0.1, 9)
        for n, m in ((z, w), (-z, w), (w, z), (-w, z)):  # face normal, second axis
            base = len(pts)
            for si in s:
                for ti in t:
                    pts.append(si * u + 0.1 * n + ti * m)
            nt = len(t)
            for i in range(len(s) - 1):
                for j in range(nt - 1):
                    q = base + i * nt + j
                    tris += [[q, q + nt, q + 1], [q + 1, q + nt, q + nt + 1]]
    return np.array(pts), np.array(tris)


def test_arms_are_found_with_their_directions():
    v, _ = star()
    lab, dirs, c, rho, big = ls.arms(v)
    assert set(lab[lab >= 0]) == set(range(5))
    angles = sorted(np.degrees(np.arctan2(dirs[:, 1], dirs[:, 0])) % 360)
    assert np.allclose(angles, sorted((90 + 72 * np.arange(5)) % 360), atol=3.0)
    assert np.all(lab[rho < ls.BODY * big] == -1)


def test_stretch_of_a_known_lengthening():
    v, tris = star()
    lab, dirs, c, rho, big = ls.arms(v)
    edges = ls.arm_edges(v, tris, lab, dirs)
    assert all(len(e) > 100 for e in edges)
    assert np.allclose(ls.stretch(v, v, edges), 1.0)
    radial = np.c_[v[:, :2] - c[:2], np.zeros(len(v))]
    assert np.allclose(ls.stretch(v + 0.05 * radial, v, edges), 1.05, atol=2e-3)


def test_a_turn_of_the_sections_is_separated_from_the_rest():
    v, _ = star()
    lab, dirs, c, rho, big = ls.arms(v)
    rng = np.random.default_rng(1)
    along = np.zeros_like(v)
    on_arm = lab >= 0
    along[on_arm] = dirs[lab[on_arm]]
    turn = -0.15 * (v[:, 2] - v[:, 2].mean())[:, None] * along  # sections turned about the across axis
    noise = 1e-3 * rng.standard_normal(v.shape)
    e = turn + noise
    vertical = lambda p, k: p[:, 2]  # noqa: E731
    in_plane = lambda p, k: p @ np.cross([0.0, 0.0, 1.0], dirs[k])  # noqa: E731
    rest, slope = ls.remove_linear(v, e, lab, dirs, rho, big, [vertical])
    assert abs(slope[0] + 0.15) < 5e-3
    assert np.abs(rest - noise).max() < 1e-3 + 0.15 * 0.1  # what remains is the noise (and the body)
    assert np.linalg.norm(rest[on_arm], axis=1).mean() < 0.2 * np.linalg.norm(e[on_arm], axis=1).mean()
    # the in-plane offset does not explain a turn about the across axis
    _, slope_plane = ls.remove_linear(v, e, lab, dirs, rho, big, [in_plane])
    assert abs(slope_plane[0]) < 5e-3
    # a random regressor removes (almost) nothing
    noise_reg = lambda p, k: rng.standard_normal(len(p))  # noqa: E731
    rest_r, _ = ls.remove_linear(v, e, lab, dirs, rho, big, [noise_reg])
    assert np.linalg.norm(rest_r, axis=1).mean() > 0.95 * np.linalg.norm(e, axis=1).mean()
