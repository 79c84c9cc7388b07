#!/usr/bin/env python3
"""Where a 2D match of the accuracy benchmark misses the known map g: draws, for each given run,
M2 (grey), phi(M1) coloured by |phi(v) - g(v)| and, for every --every-th vertex of M1, the
segment from phi(v) to g(v), so that a tangential slide along M2 shows as segments along the
outline (docs/results.md, "What the large-motion error is made of").

    error_plot.py --pair PAIRDIR [--pair ...] --run LABEL=FORWARD_DIR [--run ...] -o OUT.png
                  [--every 6] [--columns 3] [--vmax X]

One --pair for all runs, or one per run (in the same order). PAIRDIR is a pair of bench/accuracy/make_pairs.py (pair.json, source.polyline, truth.xyz,
target_resampled.polyline); FORWARD_DIR a vdb_match match output of that pair from source to
the resampled target (deformed.obj, report.json), e.g. a bench/bench_accuracy.sh
runs/PAIR/symmetric/forward. Errors are in units of 10^-3 of the unit box (the match's
placement, as score.py and docs/results.md). One panel per run, --columns per row, one colour
scale. Prints one line per run, "LABEL PAIR err MEAN motion MOTION ratio R", then the path of
the picture. Exit status 2 for bad usage or unreadable input (a 3D pair included).
"""

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points, read_run  # noqa: E402


def fail(message):
    print("error_plot.py: " + message, file=sys.stderr)
    sys.exit(2)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", action="append", required=True)
    ap.add_argument("--run", action="append", required=True, metavar="LABEL=FORWARD_DIR")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--every", type=int, default=6, help="draw every N-th segment (default 6)")
    ap.add_argument("--columns", type=int, default=3, help="panels per row (default 3)")
    ap.add_argument("--vmax", type=float, help="top of the colour scale, x 1e-3 of the box "
                    "(default: the largest 98th percentile of the runs)")
    a = ap.parse_args(argv)
    if a.every < 1 or a.columns < 1:
        fail("--every and --columns must be >= 1")
    if len(a.pair) not in (1, len(a.run)):
        fail("give one --pair, or one per --run (%d runs, %d pairs)" % (len(a.run), len(a.pair)))
    try:
        runs = []
        for i, spec in enumerate(a.run):
            pair_dir = a.pair[i if len(a.pair) > 1 else 0]
            pair = json.load(open(os.path.join(pair_dir, "pair.json")))
            if pair["dimension"] != 2:
                fail("%s is a %dD pair: only 2D pairs are drawn" % (pair["name"],
                                                                    pair["dimension"]))
            truth = read_points(os.path.join(pair_dir, "truth.xyz"), 2)
            target = read_points(os.path.join(pair_dir, "target_resampled.polyline"), 2)
            label, d, report, phi = read_run(spec, 2)
            if len(phi) != len(truth):
                fail("%s: %d vertices, g has %d" % (d, len(phi), len(truth)))
            scale = report["placement"]["scale"]
            err = np.linalg.norm(phi - truth, axis=1) * scale * 1e3
            runs.append((label, phi, err, pair["motion"]["meanWorld"] * scale * 1e3, truth,
                         target, pair["name"]))
    except (OSError, ValueError, KeyError) as e:
        fail(str(e))

    for label, _, err, motion, _, _, name in runs:
        print("%s %s err %.4g motion %.4g ratio %.3f" % (label, name, err.mean(), motion,
                                                          err.mean() / motion))

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    vmax = a.vmax or max(np.percentile(r[2], 98) for r in runs)
    # One scale for every panel: the box of all the curves drawn.
    every = np.vstack([np.vstack([r[1], r[5]]) for r in runs])
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.03 * (hi - lo).max()
    aspect = (hi[1] - lo[1] + 2 * pad) / (hi[0] - lo[0] + 2 * pad)
    cols = min(len(runs), a.columns)
    rows = (len(runs) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols + 1.0, (4.6 * aspect + 0.7) * rows
                                                  + 0.6), squeeze=False)
    for ax in axes.flat[len(runs):]:
        ax.axis("off")
    for ax, (label, phi, err, motion, truth, target, name) in zip(axes.flat, runs):
        closed = np.vstack([target, target[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color="0.75", lw=3, zorder=1)
        seg = np.stack([phi, np.roll(phi, -1, axis=0)], axis=1)
        lc = LineCollection(seg, cmap="viridis", norm=plt.Normalize(0, vmax), lw=2, zorder=2)
        lc.set_array(0.5 * (err + np.roll(err, -1)))
        ax.add_collection(lc)
        k = np.arange(0, len(phi), a.every)
        arrows = np.stack([phi[k], truth[k]], axis=1)
        ax.add_collection(LineCollection(arrows, colors="crimson", lw=0.8, zorder=3))
        ax.set_title("%s\nerr %.3g = %.2f x motion" % (label, err.mean(), err.mean() / motion),
                     fontsize=10)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        ax.axis("off")
    names = sorted(set(r[6] for r in runs))
    fig.suptitle("%s\nM2 (grey), phi(M1) coloured by |phi(v) - g(v)| (x 1e-3 of the box), "
                 "phi(v) -> g(v) (red)" % ", ".join(names), fontsize=9)
    fig.colorbar(lc, ax=axes.ravel().tolist(), shrink=0.6)
    fig.savefig(a.output, dpi=90, bbox_inches="tight")
    print(a.output)


if __name__ == "__main__":
    main()
