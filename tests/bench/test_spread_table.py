"""bench/accuracy/spread_table.py, the several-run comparison of two variants in
docs/results.md: per-run values in order, run means, geometric means of the ratios of the run
means, pairs missing from a run left out, bad input refused."""

import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "bench", "accuracy"))
import spread_table as st  # noqa: E402

HEADER = ["pair", "dim", "energy", "levels", "forward_wall_s", "reverse_wall_s", "err_mean",
          "psi_phi_mean"]


def write_run(path, rows):
    with open(path, "w") as f:
        f.write("\t".join(HEADER) + "\n")
        for pair, energy, err, psi, fwd, rev in rows:
            f.write("\t".join([pair, "3", energy, "4..7", str(fwd), str(rev), str(err), str(psi)])
                    + "\n")
    return str(path)


def test_means_ratios_and_missing_pairs(tmp_path, capsys):
    # Variant A: two runs; variant B: two runs. Pair "q" is missing from B's second run.
    a1 = write_run(tmp_path / "a1.tsv", [("p", "symmetric", 2e-3, 1e-3, 10, 20),
                                         ("q", "symmetric", 5e-3, 1e-3, 10, 10),
                                         ("p", "directional", 9e-3, 9e-3, 1, 1)])
    a2 = write_run(tmp_path / "a2.tsv", [("p", "symmetric", 4e-3, 3e-3, 20, 10),
                                         ("q", "symmetric", 5e-3, 1e-3, 10, 10)])
    b1 = write_run(tmp_path / "b1.tsv", [("p", "symmetric", 3e-3, 1e-3, 30, 30),
                                         ("q", "symmetric", 1e-3, 1e-3, 10, 10)])
    b2 = write_run(tmp_path / "b2.tsv", [("p", "symmetric", 3e-3, 0.5e-3, 30, 30)])
    label_a, runs_a = st.read_runs("old=%s,%s" % (a1, a2), "symmetric")
    label_b, runs_b = st.read_runs("new=%s,%s" % (b1, b2), "symmetric")
    assert (label_a, label_b) == ("old", "new")
    lines, ratios, n = st.table(label_a, runs_a, label_b, runs_b)
    assert n == 1  # q is not in every run
    assert lines[2] == "| p | 2 / 4 | 3 / 3 | 1 / 3 | 1 / 0.5 | 30 → 60 s |"
    # Run means: err 3 -> 3, psi 2 -> 0.75, time 30 -> 60 (the directional row is ignored).
    assert math.isclose(ratios["err"], 1.0)
    assert math.isclose(ratios["psi_phi"], 0.375)
    assert math.isclose(ratios["time"], 2.0)
    assert st.main(["--a", "old=%s,%s" % (a1, a2), "--b", "new=%s,%s" % (b1, b2)]) == 0
    out = capsys.readouterr().out
    assert "over 1 pairs" in out and "err 1.000" in out and "time 2.000" in out


def test_geometric_mean_over_pairs(tmp_path):
    a = write_run(tmp_path / "a.tsv", [("p", "symmetric", 1e-3, 1e-3, 1, 1),
                                       ("q", "symmetric", 1e-3, 1e-3, 1, 1)])
    b = write_run(tmp_path / "b.tsv", [("p", "symmetric", 4e-3, 1e-3, 1, 1),
                                       ("q", "symmetric", 1e-3, 1e-3, 1, 1)])
    _, ratios, n = st.table("a", st.read_runs("a=" + a, "symmetric")[1],
                            "b", st.read_runs("b=" + b, "symmetric")[1])
    assert n == 2
    assert math.isclose(ratios["err"], 2.0)  # sqrt(4 * 1)


def test_bad_input(tmp_path, capsys):
    a = write_run(tmp_path / "a.tsv", [("p", "symmetric", 1e-3, 1e-3, 1, 1)])
    b = write_run(tmp_path / "b.tsv", [("q", "symmetric", 1e-3, 1e-3, 1, 1)])
    assert st.main(["--a", "a=" + a, "--b", "b=" + b]) == 1  # no pair in common
    assert st.main(["--a", a, "--b", "b=" + b]) == 2  # no label
    assert st.main(["--a", "a=" + str(tmp_path / "missing.tsv"), "--b", "b=" + b]) == 2
    assert "spread_table.py:" in capsys.readouterr().err
