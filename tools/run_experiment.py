#!/usr/bin/env python3
"""Reproduces the paper's symmetry experiment (tab:inverseError) on the bundled pairs.

For each pair (S: starfish, 3D; J: the jumping figure, 2D) and each energy (dir: the directional
comparison energy eq:Ecomparison; sym: the symmetric energy eq:Esym), matches A -> B (phi) and
B -> A (psi) with `vdb_match --preset paper` (tab:parameters and the paper's levels, 3D 4..8 and
2D 4..9, without the additions of ours that change the result), then measures |psi o phi - Id| with `vdb_match consistency` (the four
columns of tab:inverseError, as fractions of the domain size) and renders pictures with
`vdb_match slice` and `vdb_match texture`. Writes OUTPUT/results.md (default docs/results.md)
with the table, the pictures (OUTPUT_DIR/results/*.png), the machine and the timings.

Usage:
  tools/run_experiment.py [--quick] [--vdb-match PATH] [--work DIR] [--output FILE] [--force]

--quick runs reduced levels (3D 3..4, 2D 4..5) for the test suite; --force recomputes matches
whose outputs already exist in the work directory (default: reuse them, the runs take minutes).
Needs the system python (json only); exits non-zero if a command fails.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

PAIRS = [
    # key, label, A, B, full levels, quick levels
    ("S", "starfish (3D)", "assets/starfish_a.vdb", "assets/starfish_b.vdb", "4..8", "3..4"),
    ("J", "figure (2D)", "assets/figure_a.polyline", "assets/figure_b.polyline", "4..9", "4..5"),
]
ENERGIES = [("dir", "directional"), ("sym", "symmetric")]
# results.md from this line on is written by hand and kept when the script rewrites the file.
HAND_WRITTEN = "<!-- Written by hand below this line; tools/run_experiment.py keeps it. -->"
# The paper's tab:inverseError, as printed (fractions of the unit box): L2(Omega), Linf(Omega),
# avg over M1, Linf over M1.
PAPER = {
    ("S", "dir"): (0.0637, 0.136, 0.0132, 0.0546),
    ("S", "sym"): (0.0473, 0.115, 0.00570, 0.0240),
    ("J", "dir"): (0.0715, 0.141, 0.0223, 0.141),
    ("J", "sym"): (0.0419, 0.0982, 0.00737, 0.0982),
}


def run(cmd, log):
    """Runs a command, appends its output to the log, returns (seconds, stdout)."""
    t0 = time.time()
    print("+ " + " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    seconds = time.time() - t0
    with open(log, "a") as f:
        f.write("$ " + " ".join(cmd) + "\n" + proc.stdout + proc.stderr + "\n")
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise SystemExit(f"run_experiment: command failed with exit code {proc.returncode}: "
                         + " ".join(cmd))
    return seconds, proc.stdout


def match(vdb, source, target, energy, levels, out, force, log, extra):
    report = os.path.join(out, "report.json")
    if os.path.exists(report) and not force:
        with open(report) as f:
            r = json.load(f)
        if (r.get("status") != "interrupted" and r["parameters"]["energy"] == energy
                and r["parameters"].get("preset") == "paper"
                and f"{r['parameters']['minLevel']}..{r['parameters']['maxLevel']}" == levels):
            print(f"reusing {out}", flush=True)
            return r
    run([vdb, source, target, "-o", out, "--preset", "paper", "--energy", energy, "--levels",
         levels, "--quiet"] + extra, log)
    with open(report) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="reduced levels (for tests)")
    ap.add_argument("--vdb-match", default=os.path.join(ROOT, "build/tools/vdb_match/vdb_match"))
    ap.add_argument("--work", default=os.path.join(ROOT, "out/experiment"))
    ap.add_argument("--output", default=os.path.join(ROOT, "docs/results.md"))
    ap.add_argument("--force", action="store_true", help="recompute existing matches")
    ap.add_argument("--no-pictures", action="store_true", help="skip slice and texture renders")
    ap.add_argument("--match-args", default="", help="extra options for every match")
    args = ap.parse_args()

    vdb = os.path.abspath(args.vdb_match)
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, "commands.log")
    pictures = os.path.join(os.path.dirname(os.path.abspath(args.output)), "results")
    os.makedirs(pictures, exist_ok=True)
    extra = args.match_args.split()

    rows, timings, figures = [], [], []
    for key, label, a, b, full, quick in PAIRS:
        levels = quick if args.quick else full
        for short, energy in ENERGIES:
            case = f"{key}-{short}"
            phi_dir = os.path.join(work, case, "ab")
            psi_dir = os.path.join(work, case, "ba")
            t0 = time.time()
            r_ab = match(vdb, a, b, energy, levels, phi_dir, args.force, log, extra)
            r_ba = match(vdb, b, a, energy, levels, psi_dir, args.force, log, extra)
            phi = os.path.join(phi_dir, "deformation.vdb")
            psi = os.path.join(psi_dir, "deformation.vdb")
            _, text = run([vdb, "consistency", phi, psi, "--source", a, "--target", b, "--json"],
                          log)
            c = json.loads(text)
            rows.append((key, short, label, energy, levels, c, r_ab, r_ba))
            timings.append((case, r_ab["result"]["seconds"]["match"],
                            r_ba["result"]["seconds"]["match"], time.time() - t0))
            if not args.no_pictures:
                stem = os.path.join(pictures, case)
                # The EXR and the other channels stay in the work directory.
                slice_stem = os.path.join(work, case, "slice")
                run([vdb, "slice", phi, "--source", a, "--target", b, "--inverse", psi,
                     "-o", slice_stem + ".exr"], log)
                tex = os.path.join(work, case, "texture")
                run([vdb, "texture", phi, "--source", a, "--inverse", psi, "--target", b,
                     "-o", tex], log)
                summary = os.path.join(tex, "summary.png")
                if os.path.exists(summary):
                    shutil.copyfile(summary, stem + "-texture.png")
                    figures.append((case, os.path.basename(stem + "-texture.png")))
                preview = slice_stem + ".inverse_error.png"
                if os.path.exists(preview):
                    shutil.copyfile(preview, stem + "-slice-inverse-error.png")
                    figures.append((case + ": |ψ∘φ − Id| on the slice z = centre of M1",
                                    case + "-slice-inverse-error.png"))

    write_markdown(args, rows, timings, figures, pictures)
    print(f"run_experiment: wrote {args.output}")


def fmt(x):
    return "—" if x is None else f"{x:.3g}"


def columns(c):
    """The four columns of tab:inverseError from the consistency JSON (fractions of the box)."""
    rel = c["psi_phi"]["relative"]
    return (rel["omega_l2"], rel["omega_linf"], rel["shape_mean"], rel["shape_max"])


def write_markdown(args, rows, timings, figures, pictures):
    out = []
    out.append("# Results: the paper's symmetry experiment on the bundled pairs\n")
    out.append("Generated by `tools/run_experiment.py" + (" --quick" if args.quick else "")
               + "`; every number below comes from that run. φ matches A → B, ψ matches "
               "B → A, both with the same energy; |ψ∘φ − Id| is measured by `vdb_match "
               "consistency` (exact piecewise-linear composition), as a fraction of the side "
               "of the unit box Ω (the paper's units).\n")
    out.append(f"Machine: {platform.node()}, {os.cpu_count()} cores, "
               f"{platform.processor() or platform.machine()}, {platform.platform()}.\n")
    out.append("## tab:inverseError\n")
    out.append("| case | levels | ‖ψ∘φ − Id‖_L²(Ω) | ‖ψ∘φ − Id‖_L∞(Ω) | avg(\\|ψ∘φ − Id\\|, M1) | "
               "‖ψ∘φ − Id‖_L∞(M1) | paper (same columns) |")
    out.append("|---|---|---|---|---|---|---|")
    for key, short, label, energy, levels, c, r_ab, r_ba in rows:
        l2, linf, avg, mmax = columns(c)
        paper = PAPER.get((key, short))
        ptxt = " / ".join(fmt(x) for x in paper) if paper else ""
        out.append(f"| {key}, {short} ({label}) | {levels} | {fmt(l2)} | {fmt(linf)} | "
                   f"{fmt(avg)} | {fmt(mmax)} | {ptxt} |")
    out.append("")
    out.append("Ratio dir / sym of the average over M1 (the paper reports 2 to 4):\n")
    by = {(k, s): columns(c) for k, s, *_rest, c, _a, _b in
          [(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7]) for r in rows]}
    for key, label, *_ in PAIRS:
        if (key, "dir") in by and (key, "sym") in by and by[(key, "sym")][2] > 0:
            out.append(f"- {label}: {by[(key, 'dir')][2] / by[(key, 'sym')][2]:.2f}")
    out.append("")
    out.append("## Matching quality\n")
    out.append("| case | direction | status | energy | residual mean / max (unit box) | "
               "min det Dφ | finest-level unknowns (% of dense nodes) | time [s] |")
    out.append("|---|---|---|---|---|---|---|---|")
    for key, short, label, energy, levels, c, r_ab, r_ba in rows:
        for name, r in (("A→B", r_ab), ("B→A", r_ba)):
            last = r["levels"][-1]
            res = r["result"]["residual"]
            out.append(f"| {key}, {short} | {name} | {r['status']} | {r['result']['energy']:.4g} | "
                       f"{res['meanUnit']:.2e} / {res['maxUnit']:.2e} | "
                       f"{r['result']['minJacobian']:.3f} | {last['unknowns']} "
                       f"({100 * last['nodeFractionOfDense']:.1f}%) | "
                       f"{r['result']['seconds']['match']:.1f} |")
    out.append("")
    out.append("## Pictures\n")
    if not figures:
        out.append("(none: run without --no-pictures)\n")
    for caption, name in figures:
        out.append(f"**{caption}**\n\n![{caption}](results/{name})\n")
    # Sections written by hand after HAND_WRITTEN (discussion, peer comparisons) are kept.
    kept = ""
    if os.path.exists(args.output):
        with open(args.output) as f:
            previous = f.read()
        if HAND_WRITTEN in previous:
            kept = "\n" + previous[previous.index(HAND_WRITTEN):]
    with open(args.output, "w") as f:
        f.write("\n".join(out) + "\n" + kept)


if __name__ == "__main__":
    main()
