#!/usr/bin/env python3
"""Compare two variants of vdb_match over several runs each, as docs/results.md does where a
single run is not enough: one perturbation that changes no method (one anchor more or less,
--anchor-count 99 / 100 / 101) moves these matches by up to 20%, so a difference of one run
says little. Each variant is given as several bench/bench_accuracy.sh results.tsv files (the
same pairs, one file per run); prints, per pair present in every file, the err mean and
|psi o phi - Id| of every run (x 1e-3 of the unit box) and the forward plus reverse wall time
(mean of the runs), then the geometric means over the pairs of the ratios B / A of the run
means.

Usage:
  spread_table.py --a LABEL=RUN1.tsv,RUN2.tsv,... --b LABEL=RUN1.tsv,RUN2.tsv,...
                  [--energy symmetric]
Prints Markdown. Exit status 2 for bad usage or unreadable files, 1 if no pair is in every file.
"""

import argparse
import csv
import math
import sys


def read_runs(spec, energy):
    """LABEL=a.tsv,b.tsv -> (label, [ {pair: row}, ... ]) with the rows of @a energy."""
    if "=" not in spec:
        raise ValueError("expected LABEL=RUN1.tsv,RUN2.tsv,..., got %r" % spec)
    label, files = spec.split("=", 1)
    runs = []
    for path in files.split(","):
        with open(path) as f:
            rows = [r for r in csv.DictReader(f, delimiter="\t") if r.get("energy") == energy]
        runs.append({r["pair"]: r for r in rows})
    if not runs:
        raise ValueError("no results files in %r" % spec)
    return label, runs


def column(runs, pair, key, scale=1.0):
    return [scale * float(run[pair][key]) for run in runs]


def mean(values):
    return sum(values) / len(values)


def table(a_label, a_runs, b_label, b_runs):
    """The Markdown lines and the geometric means {err, psi_phi, time} of the ratios B / A."""
    pairs = [p for p in a_runs[0] if all(p in run for run in a_runs + b_runs)]
    runs = lambda v: " / ".join("%.3g" % x for x in v)  # noqa: E731
    lines = [
        "| pair | err mean, %s | %s | \\|ψ∘φ − Id\\|, %s | %s | time, %s → %s |"
        % (a_label, b_label, a_label, b_label, a_label, b_label),
        "|---|---|---|---|---|---|",
    ]
    logs = {"err": [], "psi_phi": [], "time": []}
    for p in pairs:
        ea, eb = column(a_runs, p, "err_mean", 1e3), column(b_runs, p, "err_mean", 1e3)
        ca, cb = column(a_runs, p, "psi_phi_mean", 1e3), column(b_runs, p, "psi_phi_mean", 1e3)
        ta = [f + r for f, r in zip(column(a_runs, p, "forward_wall_s"),
                                    column(a_runs, p, "reverse_wall_s"))]
        tb = [f + r for f, r in zip(column(b_runs, p, "forward_wall_s"),
                                    column(b_runs, p, "reverse_wall_s"))]
        logs["err"].append(math.log(mean(eb) / mean(ea)))
        logs["psi_phi"].append(math.log(mean(cb) / mean(ca)))
        logs["time"].append(math.log(mean(tb) / mean(ta)))
        lines.append("| %s | %s | %s | %s | %s | %.0f → %.0f s |"
                     % (p, runs(ea), runs(eb), runs(ca), runs(cb), mean(ta), mean(tb)))
    ratios = {k: math.exp(mean(v)) for k, v in logs.items()} if pairs else {}
    return lines, ratios, len(pairs)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--a", required=True, metavar="LABEL=TSV,...")
    ap.add_argument("--b", required=True, metavar="LABEL=TSV,...")
    ap.add_argument("--energy", default="symmetric")
    args = ap.parse_args(argv)
    try:
        a_label, a_runs = read_runs(args.a, args.energy)
        b_label, b_runs = read_runs(args.b, args.energy)
        lines, ratios, n = table(a_label, a_runs, b_label, b_runs)
    except (OSError, ValueError, KeyError) as e:
        print("spread_table.py: %s" % e, file=sys.stderr)
        return 2
    if n == 0:
        print("spread_table.py: no pair is in every results file", file=sys.stderr)
        return 1
    print("\n".join(lines))
    print("\nGeometric means over %d pairs of the ratios %s / %s of the run means: err %.3f, "
          "|psi o phi - Id| %.3f, time %.3f." % (n, b_label, a_label, ratios["err"],
                                                 ratios["psi_phi"], ratios["time"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
