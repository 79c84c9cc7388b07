"""bench/accuracy/correspondence_table.py, the large-motion goal of docs/results.md: at most
0.25x the motion, det D phi > 0 and both mean residuals below h/2 (the target residual only where
the results have it)."""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import correspondence_table as ct  # noqa: E402

H9 = 2.0 ** -9


def row(err, motion=1e-2, det=0.1, resid=0.1 * H9, target=None):
    r = {"err_mean": str(err), "motion_mean": str(motion), "min_det": str(det),
         "residual_mean": str(resid), "levels": "4..9"}
    if target is not None:
        r["target_residual_mean"] = str(target)
    return r


def test_ratio_alone_decides_when_the_residuals_are_small():
    assert ct.large_motion_verdict(row(2.4e-3)) == (True, "met (0.24 x motion)")
    assert ct.large_motion_verdict(row(2.6e-3)) == (False, "not met (0.26 x motion)")
    assert ct.large_motion_verdict(row(2.4e-3, target=0.2 * H9))[0]


def test_a_residual_either_way_or_a_fold_fails_the_goal():
    ok, text = ct.large_motion_verdict(row(2.0e-3, target=0.6 * H9))
    assert not ok and text.startswith("not met (0.20 x motion; target residual")
    ok, text = ct.large_motion_verdict(row(2.0e-3, resid=0.5 * H9))
    assert not ok and "residual 0.000977 > h/2" in text
    ok, text = ct.large_motion_verdict(row(2.0e-3, det=0.0))
    assert not ok and "min det 0" in text
    # h is the finest level's: at 4..7 the same target residual is below h/2
    r = row(2.0e-3, target=0.6 * H9)
    r["levels"] = "4..7"
    assert ct.large_motion_verdict(r)[0]


def test_results_without_the_target_residual_are_judged_on_the_rest():
    assert ct.large_motion_verdict(row(2.0e-3, target="nan"))[0]
    assert ct.large_motion_verdict(row(2.0e-3, target=""))[0]
