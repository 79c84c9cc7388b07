"""bench/accuracy/elastix.sh, the elastix registration that bench/compare_elastix.sh (3D) and
bench/compare_peers.sh --elastix (2D and 3D) share: one parameter file per dimension, with one
value per axis and resolution, and a refusal of a schedule that does not match the pyramid."""

import os
import re
import subprocess

import pytest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy", "elastix.sh")


def parameters(tmp_path, dim, env=None):
    out = tmp_path / f"p{dim}.txt"
    subprocess.run(["bash", "-c", f'source "{SCRIPT}" && elastix_check && elastix_parameters {dim} "{out}"'],
                   check=True, env={**os.environ, **(env or {})})
    entries = {}
    for line in out.read_text().splitlines():
        m = re.match(r"\((\w+) (.*)\)$", line.strip())
        if m:
            entries[m.group(1)] = m.group(2).split()
    return entries


@pytest.mark.parametrize("dim", [2, 3])
def test_one_value_per_axis_and_resolution(tmp_path, dim):
    p = parameters(tmp_path, dim)
    assert p["FixedImageDimension"] == [str(dim)] and p["MovingImageDimension"] == [str(dim)]
    assert p["NumberOfResolutions"] == ["4"]
    assert p["ImagePyramidSchedule"] == [f for f in "8421" for _ in range(dim)]
    assert p["GridSpacingSchedule"] == [f for f in "8421" for _ in range(dim)]
    assert p["FinalGridSpacingInVoxels"] == ["4"] * dim
    assert p["Metric"] == ['"AdvancedMeanSquares"', '"TransformBendingEnergyPenalty"']
    assert p["Metric1Weight"] == ["3e-6"]
    assert p["MaximumNumberOfIterations"] == ["250"]


def test_the_environment_overrides_and_no_penalty(tmp_path):
    p = parameters(tmp_path, 3, {"ELASTIX_PYRAMID": "4 2 1", "ELASTIX_GRID_SCHEDULE": "4 2 1",
                                 "ELASTIX_BENDING": "0", "ELASTIX_ITERATIONS": "500"})
    assert p["NumberOfResolutions"] == ["3"]
    assert p["ImagePyramidSchedule"] == ["4"] * 3 + ["2"] * 3 + ["1"] * 3
    assert p["Metric"] == ['"AdvancedMeanSquares"'] and "Metric1Weight" not in p
    assert p["MaximumNumberOfIterations"] == ["500"]


def test_a_schedule_that_does_not_match_the_pyramid_is_refused(tmp_path):
    r = subprocess.run(["bash", "-c", f'source "{SCRIPT}" && elastix_check'],
                       env={**os.environ, "ELASTIX_PYRAMID": "8 4 2 1", "ELASTIX_GRID_SCHEDULE": "4 2 1"},
                       capture_output=True, text=True)
    assert r.returncode != 0 and "one value per resolution" in r.stderr
