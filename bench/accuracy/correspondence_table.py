#!/usr/bin/env python3
"""The correspondence table of docs/results.md from benchmark outputs: mean |phi(v) - g(v)| over
the source's vertices (x 1e-3 of the unit box) per pair, for one or more vdb_match runs
(bench/bench_accuracy.sh results.tsv) and the peers (bench/compare_peers.sh peers.tsv,
bench/compare_elastix.sh --tsv), with the correspondence issue's goal per pair kind
(make_pairs.py pair.json "kind"):
  near-isometric  vdb_match at or below the best peer on the pair
  large motion    vdb_match at or below 0.25 x the mean motion |g(v) - v|, with det D phi > 0
                  and the mean residual below h/2 (h of the finest level), both ways where the
                  results have it: |d2(phi(v))| over M1 and, since 2026-11-28, the distance of
                  M2's vertices to phi(M1) (target_residual_mean)
  stretch         no goal (reported)

Usage:
  correspondence_table.py --pairs-dir DIR/pairs [--vdbmatch LABEL=RESULTS.tsv ...]
                          [--peers PEERS.tsv ...] [--energy symmetric] [--goal LABEL]
--vdbmatch may be repeated (columns in that order); the goal is judged on --goal (default the
first). Rows follow the order of the first vdb_match file. Prints Markdown.
"""

import argparse
import csv
import json
import os
import sys

LARGE_MOTION_GOAL = 0.25  # err mean <= this x motion mean


def large_motion_verdict(r):
    """(ok, text) of the large-motion goal for one results.tsv row: err_mean at most
    LARGE_MOTION_GOAL x motion_mean, min_det > 0, residual_mean and (when the row has it)
    target_residual_mean below h/2, h = 2^-B for levels A..B."""
    ratio = float(r["err_mean"]) / float(r["motion_mean"])
    half = 0.5 * 2.0 ** -int(r["levels"].split("..")[1])
    misses = []
    if not float(r["min_det"]) > 0:
        misses.append("min det %.3g" % float(r["min_det"]))
    if not float(r["residual_mean"]) < half:
        misses.append("residual %.3g > h/2" % float(r["residual_mean"]))
    target = r.get("target_residual_mean")
    if target not in (None, "", "nan") and not float(target) < half:
        misses.append("target residual %.3g > h/2" % float(target))
    ok = ratio <= LARGE_MOTION_GOAL and not misses
    return ok, ("met" if ok else "not met") + " (%s)" % "; ".join(
        ["%.2f x motion" % ratio] + misses)


def read_tsv(path):
    with open(path) as f:
        return list(csv.DictReader(f, delimiter="\t"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs-dir", required=True)
    ap.add_argument("--vdbmatch", action="append", default=[], metavar="LABEL=TSV")
    ap.add_argument("--peers", action="append", default=[], metavar="TSV")
    ap.add_argument("--energy", default="symmetric")
    ap.add_argument("--goal", default=None, metavar="LABEL")
    args = ap.parse_args()

    runs = []  # (label, {pair: row})
    order = []
    for item in args.vdbmatch:
        if "=" not in item:
            sys.exit("correspondence_table.py: --vdbmatch wants LABEL=RESULTS.tsv, got " + item)
        label, path = item.split("=", 1)
        rows = [r for r in read_tsv(path) if r["energy"] == args.energy]
        runs.append((label, {r["pair"]: r for r in rows}))
        order += [r["pair"] for r in rows if r["pair"] not in order]
    peers = {}  # peer -> {pair: row}
    for path in args.peers:
        for r in read_tsv(path):
            peers.setdefault(r["peer"], {})[r["pair"]] = r
            if r["pair"] not in order:
                order.append(r["pair"])
    goal = args.goal or (runs[0][0] if runs else None)
    goal_run = dict(runs).get(goal) if goal else None
    peer_names = sorted(peers)

    head = ["pair", "kind", "motion"] + [label for label, _ in runs] + peer_names
    if goal_run is not None:
        head.append("goal (%s)" % goal)
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    met = total = 0
    for pair in order:
        pj = os.path.join(args.pairs_dir, pair, "pair.json")
        kind = json.load(open(pj)).get("kind", "?") if os.path.exists(pj) else "?"
        motion = None
        cells = []
        for _, rows in runs:
            r = rows.get(pair)
            cells.append("%.3g" % (1e3 * float(r["err_mean"])) if r else "")
            if r and motion is None and r.get("motion_mean"):  # tables of err_mean only lack it
                motion = float(r["motion_mean"])
        best_peer, best_name = None, None
        for name in peer_names:
            r = peers[name].get(pair)
            if r is None:
                cells.append("")
                continue
            e = float(r["err_mean"])
            cells.append("%.3g" % (1e3 * e))
            if motion is None:
                motion = float(r["motion_mean"])
            if best_peer is None or e < best_peer:
                best_peer, best_name = e, name
        # bold the best of the row
        values = [float(c) if c else None for c in cells]
        finite = [v for v in values if v is not None]
        if finite:
            lo = min(finite)
            cells = ["**%s**" % c if v == lo else c for c, v in zip(cells, values)]
        row = [pair, kind, "%.3g" % (1e3 * motion) if motion is not None else ""] + cells
        if goal_run is not None:
            r = goal_run.get(pair)
            verdict = ""
            if r is not None:
                e = float(r["err_mean"])
                if kind == "near-isometric" and best_peer is not None:
                    total += 1
                    ok = e <= best_peer
                    met += ok
                    verdict = "met" if ok else "%.2f x %s" % (e / best_peer, best_name)
                elif kind == "large motion":
                    total += 1
                    ok, verdict = large_motion_verdict(r)
                    met += ok
            row.append(verdict)
        print("| " + " | ".join(row) + " |")
    if goal_run is not None:
        print("\nGoal met on %d of %d pairs (near-isometric: at or below the best peer; large "
              "motion: at most %.2f x the motion, det D phi > 0, mean residuals below h/2)."
              % (met, total, LARGE_MOTION_GOAL))


if __name__ == "__main__":
    main()
