#!/usr/bin/env python3
"""Scores one forward/reverse match of a synthetic pair (bench/bench_accuracy.sh) against the
ground truth g written by make_pairs.py.

    score.py --header
    score.py --pair PAIRDIR --forward DIR --reverse DIR --consistency JSON --energy E
             --levels A..B --wall S --reverse-wall S [--tsv FILE]

Prints one table row. All lengths are in unit-box units (the match's placement:
unit = scale * (world - worldOrigin), so a world length is multiplied by placement.scale):
  resid       result.residual.meanUnit of the forward report: mean |d2(phi(v))| over M1
              (--tsv also: target_residual_mean and target_far_share, its mirror
              result.targetResidual: M2's vertices to phi(M1); the status says "M2 not reached"
              when more than 1% of them are farther than sigma)
  err mean/p95  mean and 95th percentile of |phi(v) - g(v)| over M1's vertices, phi(v) read
              from the forward deformed.obj (same vertex order as the source file)
  rev err     mean |psi(g(v)) - v| over M2's vertices (the reverse match against g^-1)
  motion      mean |g(v) - v| (pair.json), for reference
  psi.phi     mean |psi(phi(v)) - v| over M1's vertices (vdb_match consistency,
              psi_phi.relative.shape_mean: relative to the domain size = 1/scale)
  min det     result.minJacobian of the forward report
--tsv also splits the error between the vertices g keeps still (|g(v) - v| < STILL, 5e-3 of the
unit box) and those it moves: err_still_mean, err_moving_mean, still_fraction (of the vertices)
and still_error_share (of the summed error). A large share on still vertices means the match
drags what stays along with what moves (docs/results.md, "What limits the correspondence").
--tsv appends the same figures (and a few more) as a tab-separated line, with a header if the
file is new.
"""

import argparse
import json
import os
import sys

import numpy as np

STILL = 5e-3  # unit-box units: a vertex g moves by less is "still"

COLUMNS = ("pair", "dim", "energy", "levels", "fwd s", "rev s", "resid", "err mean", "err p95",
           "rev err", "motion", "psi.phi", "min det", "status")
WIDTHS = (21, 3, 11, 6, 7, 7, 9, 9, 9, 9, 9, 9, 7, 0)


def row(values):
    return " ".join(("%-*s" if i < 4 else "%*s") % (w, v) if w else str(v)
                    for i, (w, v) in enumerate(zip(WIDTHS, values))).rstrip()


def read_points(path, dim):
    """Vertices of an OBJ (v lines), a polyline (x y lines) or an xyz file, in file order."""
    pts = []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts or parts[0].startswith("#"):
                continue
            if parts[0] == "v":
                parts = parts[1:]
            elif not parts[0][0].isdigit() and parts[0][0] not in "+-.":
                continue
            pts.append([float(p) for p in parts[:dim]])
    return np.array(pts, dtype=float)


def read_run(spec, dim):
    """A --run LABEL=FORWARD_DIR of the diagnosis scripts -> (label, FORWARD_DIR, its report.json,
    the vertices of its deformed.obj). ValueError for a spec without '='."""
    if "=" not in spec:
        raise ValueError("--run expects LABEL=FORWARD_DIR, got %r" % spec)
    label, d = spec.split("=", 1)
    with open(os.path.join(d, "report.json")) as f:
        report = json.load(f)
    return label, d, report, read_points(os.path.join(d, "deformed.obj"), dim)


def fail(message):
    sys.exit("score.py: " + message)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--header", action="store_true")
    ap.add_argument("--pair")
    ap.add_argument("--forward")
    ap.add_argument("--reverse")
    ap.add_argument("--consistency")
    ap.add_argument("--energy")
    ap.add_argument("--levels")
    ap.add_argument("--wall", type=float)
    ap.add_argument("--reverse-wall", type=float)
    ap.add_argument("--tsv")
    ap.add_argument("--reverse-points",
                    help="psi(g(v)) in the order of the source's vertices (default: the reverse "
                         "match's deformed.obj, when its source was target.obj)")
    a = ap.parse_args()
    if a.header:
        print(row(COLUMNS))
        print("-" * len(row(COLUMNS)))
        return
    pair = json.load(open(os.path.join(a.pair, "pair.json")))
    dim = pair["dimension"]
    ext = "obj" if dim == 3 else "polyline"
    source = read_points(os.path.join(a.pair, "source." + ext), dim)
    truth = read_points(os.path.join(a.pair, "truth.xyz"), dim)
    fwd = json.load(open(os.path.join(a.forward, "report.json")))
    phi = read_points(os.path.join(a.forward, "deformed.obj"), dim)
    psi_g = read_points(a.reverse_points or os.path.join(a.reverse, "deformed.obj"), dim)
    cons = json.load(open(a.consistency))
    if not (len(source) == len(truth) == len(phi) == len(psi_g)):
        fail("%s: vertex counts differ (source %d, truth %d, forward deformed %d, reverse "
             "deformed %d): the deformed meshes do not keep the input's vertices"
             % (pair["name"], len(source), len(truth), len(phi), len(psi_g)))
    scale = fwd["placement"]["scale"]
    err = np.linalg.norm(phi - truth, axis=1) * scale
    rev_err = np.linalg.norm(psi_g - source, axis=1) * scale
    motion = pair["motion"]["meanWorld"] * scale
    still = np.linalg.norm(truth - source, axis=1) * scale < STILL
    resid = fwd["result"]["residual"]["meanUnit"]
    psiphi = cons["psi_phi"]["relative"]["shape_mean"]
    min_det = fwd["result"]["minJacobian"]
    status = fwd["status"]
    rev = json.load(open(os.path.join(a.reverse, "report.json")))
    if rev["status"] != "converged":
        status += ", reverse " + rev["status"]
    # a sanity check of the order: phi should be much closer to g than to the identity
    if err.mean() > 0.9 * motion:
        status += ", err > 0.9 motion"
    # the mirror of resid (vdb_match reports it since 2026-11-28): M2's vertices to phi(M1)
    target = fwd["result"].get("targetResidual", {})
    target_mean = target.get("meanUnit", float("nan"))
    target_far = target.get("farShare", float("nan"))
    if target_far > 0.01:
        status += ", M2 not reached (%.1f%% far)" % (100 * target_far)
    print(row((pair["name"], "%dD" % dim, a.energy, a.levels, "%.1f" % a.wall,
               "%.1f" % a.reverse_wall, "%.2e" % resid, "%.2e" % err.mean(),
               "%.2e" % np.percentile(err, 95), "%.2e" % rev_err.mean(), "%.2e" % motion,
               "%.2e" % psiphi, "%.3f" % min_det, status)))
    sys.stdout.flush()
    if a.tsv:
        fields = {
            "pair": pair["name"], "dim": dim, "energy": a.energy, "levels": a.levels,
            "forward_wall_s": a.wall, "reverse_wall_s": a.reverse_wall,
            "residual_mean": resid, "residual_max": fwd["result"]["residual"]["maxUnit"],
            "err_mean": float(err.mean()), "err_p95": float(np.percentile(err, 95)),
            "err_max": float(err.max()), "reverse_err_mean": float(rev_err.mean()),
            "reverse_err_p95": float(np.percentile(rev_err, 95)), "motion_mean": motion,
            "psi_phi_mean": psiphi, "psi_phi_max": cons["psi_phi"]["relative"]["shape_max"],
            "phi_psi_mean": cons["phi_psi"]["relative"]["shape_mean"],
            "min_det": min_det, "reverse_min_det": rev["result"]["minJacobian"],
            "forward_iterations": sum(l["iterations"] for l in fwd["levels"]),
            "status": fwd["status"], "reverse_status": rev["status"],
            "still_fraction": float(still.mean()),
            "err_still_mean": float(err[still].mean()) if still.any() else float("nan"),
            "err_moving_mean": float(err[~still].mean()) if (~still).any() else float("nan"),
            "still_error_share": float(err[still].sum() / err.sum()) if err.sum() > 0 else 0.0,
            "target_residual_mean": float(target_mean), "target_far_share": float(target_far),
        }
        new = not os.path.exists(a.tsv)
        with open(a.tsv, "a") as f:
            if new:
                f.write("\t".join(fields) + "\n")
            f.write("\t".join(("%.6g" % v) if isinstance(v, float) else str(v)
                              for v in fields.values()) + "\n")


if __name__ == "__main__":
    main()
