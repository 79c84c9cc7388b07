#!/usr/bin/env python3
"""Scores a `vdb_match batch --sequence` run on make_sequence.py's frames (bench/bench_sequence.sh).

    score_sequence.py SEQDIR BATCHDIR LABEL

Prints one row per job and a summary row. Lengths are in unit-box units of each job's placement
(report.json placement.scale; the composed errors in those of the first job):
  match s     result.seconds.match of the job's report
  levels      iterations per level
  step err    mean and 95th percentile of |phi_k(v) - v'| over frame k's vertices v, v' the same
              vertex in frame k+1 (phi_k(v) read from the job's deformed.obj)
  composed    mean |phi_k o ... o phi_1(v) - v_k| over frame 1's vertices (batch collect's
              sequence/deformed.####.obj against frame k+1): the drift of the tracked surface
  min det     result.minJacobian
"""

import json
import os
import sys


def vertices(path):
    import numpy as np
    return np.array([[float(x) for x in line.split()[1:4]] for line in open(path)
                     if line.startswith("v ")])


def main():
    import numpy as np
    if len(sys.argv) != 4:
        sys.exit("usage: score_sequence.py SEQDIR BATCHDIR LABEL")
    seq, batch, label = sys.argv[1:4]
    plan = json.load(open(os.path.join(batch, "plan.json")))
    first = plan["firstFrame"]
    jobs = plan["jobs"]
    frame = lambda k: vertices(os.path.join(seq, "frame.%04d.obj" % k))
    total, steps, composed = 0.0, [], []
    scale0 = None
    for i, job in enumerate(jobs):
        d = os.path.join(batch, "jobs", job["name"])
        r = json.load(open(os.path.join(d, "report.json")))
        scale = r["placement"]["scale"]
        scale0 = scale0 or scale
        k = first + i
        e = np.linalg.norm(vertices(os.path.join(d, "deformed.obj")) - frame(k + 1), axis=1) * scale
        c = np.linalg.norm(vertices(os.path.join(batch, "sequence", "deformed.%04d.obj" % (k + 1)))
                           - frame(k + 1), axis=1) * scale0
        seconds = r["result"]["seconds"]["match"]
        total += seconds
        steps.append(e.mean())
        composed.append(c.mean())
        print("%-6s %2d->%-2d %7.1f %-22s %9.3e %9.3e %9.3e %7.3f%s"
              % (label, k, k + 1, seconds, "/".join(str(l["iterations"]) for l in r["levels"]),
                 e.mean(), np.percentile(e, 95), c.mean(), r["result"]["minJacobian"],
                 "  warm" if job.get("warmStarted") else ""))
    print("%-6s total %7.1f s, step err mean %.3e, composed err at the last frame %.3e"
          % (label, total, float(np.mean(steps)), composed[-1]))


if __name__ == "__main__":
    main()
