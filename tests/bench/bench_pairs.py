"""Shared by the benchmark tests that match generated pairs (tests/bench/test_auto_anchors.py,
test_rigid_limbs.py): the paths of bench/accuracy (put on sys.path, so that its score.py and
limb_twist.py import) and generate_and_match()."""

import json
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ACCURACY = os.path.join(HERE, "..", "..", "bench", "accuracy")
MAKE_PAIRS = os.path.join(ACCURACY, "make_pairs.py")
if ACCURACY not in sys.path:
    sys.path.insert(0, ACCURACY)


def generate_and_match(root, name, variants, levels="4..7", threads=1):
    """make_pairs.py --only name into root, then one forward match of the source onto the
    independently sampled target per variant (its extra options) at levels; returns the pair's
    directory and {variant: run directory}."""
    vdb_match = os.environ.get("VDB_MATCH")
    if not vdb_match:
        pytest.fail("VDB_MATCH (the vdb_match executable) is not set")
    subprocess.run([sys.executable, MAKE_PAIRS, str(root / "pairs"), "--only", name], check=True,
                   stdout=subprocess.DEVNULL)
    pair = root / "pairs" / name
    ext = "obj" if json.load(open(pair / "pair.json"))["dimension"] == 3 else "polyline"
    out = {}
    for label, extra in variants.items():
        run = root / label
        subprocess.run([vdb_match, "match", str(pair / ("source." + ext)),
                        str(pair / ("target_resampled." + ext)), "-o", str(run), "--levels",
                        levels, "--threads", str(threads), "--quiet"] + extra, check=True)
        out[label] = run
    return pair, out
