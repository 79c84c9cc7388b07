#!/usr/bin/env python3
"""A frame sequence with a known map between every two frames, for the sequence benchmark
(bench/bench_sequence.sh; issue: many shapes, warm starts along a sequence).

The creature of make_pairs.py animated by a skeleton-driven smooth flow stopped at the times
t_k = (k - 1) / (N - 1), k = 1..N: arm 0 curls up 75 deg, arm 2 down 55 deg and arm 3 swings
45 deg in the plane (each about a joint, blended as in make_pairs.limb_rotation), while the
whole creature drifts by (0.12, 0.06, 0) per unit time, so that the pairs of frames are placed
differently in the unit box. Every frame is the first frame's mesh moved (same vertex order and
connectivity), so vertex i of frame k corresponds to vertex i of every other frame.

--motion arm-up: instead, the large articulated motion of make_pairs.creature_arm_up (arm 0
raised 100 deg about its joint, no drift) in equal steps; its last frame is that pair's target.

Checks, as make_pairs.py: det Dg > 0 (central differences) on the vertices and on a grid around
the shape for the motion to the last frame; every frame closed, outward and free of
self-intersections.

Output: OUTDIR/frame.####.obj (k = 1..N) and OUTDIR/sequence.json (description, motion per
step and in all as fractions of the first frame's bounding-box diagonal).

Usage (system python, which has numpy and pyopenvdb):
    /usr/bin/python3 bench/accuracy/make_sequence.py OUTDIR [--frames N] [--motion limbs|arm-up]
    (default 9 frames, limbs)
Deterministic.
"""

import json
import os
import sys
import time

import numpy as np

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_pairs as mp  # noqa: E402

DRIFT = np.array([0.12, 0.06, 0.0])   # world units per unit time
LIMBS = ((0, "up", 75.0), (2, "down", 55.0), (3, "swing", 45.0))
# --motion arm-up: make_pairs.creature_arm_up (arm 0 raised 100 deg, no drift) in steps, the
# large articulated motion that a single match does not follow
ARM_UP = ((0, "up", 100.0),)


def motion_until(t_end, limbs=LIMBS, drift=DRIFT):
    """g_t: the creature's motion from the first frame to time t_end in [0, 1]."""
    maps = []
    for i, kind, degrees in limbs:
        d = mp.arm(i)
        axis = mp.UP if kind == "swing" else np.cross(d, mp.UP) * (1.0 if kind == "up" else -1.0)
        maps.append(mp.limb_rotation(0.33 * d, d, degrees, start=0.45 - 0.33, ramp=0.05,
                                     lateral=mp.window(0.26), axis=axis, plane_normal=mp.UP,
                                     t_end=t_end))
    maps.append(lambda x: x + t_end * drift)
    return mp.compose(*maps)


def main():
    args = sys.argv[1:]
    usage = "usage: make_sequence.py OUTDIR [--frames N] [--motion limbs|arm-up]"
    frames = 9
    limbs, drift, motion = LIMBS, DRIFT, "limbs"
    if "--motion" in args:
        at = args.index("--motion")
        if at + 1 >= len(args) or args[at + 1] not in ("limbs", "arm-up"):
            sys.exit(usage)
        motion = args[at + 1]
        if motion == "arm-up":
            limbs, drift = ARM_UP, np.zeros(3)
        del args[at:at + 2]
    if "--frames" in args:
        at = args.index("--frames")
        try:
            frames = int(args[at + 1])
        except (IndexError, ValueError):
            sys.exit(usage)
        del args[at:at + 2]
    if len(args) != 1 or args[0].startswith("-") or frames < 2:
        sys.exit(usage)
    out_dir = args[0]
    os.makedirs(out_dir, exist_ok=True)
    t0 = time.time()
    points, tris = mp.creature_mesh()
    points = np.round(points, mp.DECIMALS)
    mp.check_closed_oriented(points, tris, "creature")
    g_last = motion_until(1.0, limbs, drift)
    det_vertices = mp.min_jacobian(g_last, points)
    det_grid = mp.min_jacobian(g_last, mp.probe_grid(points, mp.JACOBIAN_GRID[0]))
    if not (det_vertices > 0.0 and det_grid > 0.0):
        raise RuntimeError("the motion folds (min det Dg %g on the vertices, %g on the grid)"
                           % (det_vertices, det_grid))
    diag = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    previous = points
    steps = []
    for k in range(1, frames + 1):
        t = (k - 1) / (frames - 1)
        frame = np.round(motion_until(t, limbs, drift)(points), mp.DECIMALS) if k > 1 else points
        name = "frame k=%d" % k
        mp.check_closed_oriented(frame, tris, name)
        crossings, _ = mp.self_intersections(frame, tris)
        if crossings:
            raise RuntimeError("%s intersects itself (%d crossings)" % (name, crossings))
        mp.write_obj(os.path.join(out_dir, "frame.%04d.obj" % k), frame, tris,
                     "creature sequence, frame %d of %d (t = %.4f)" % (k, frames, t))
        if k > 1:
            step = np.linalg.norm(frame - previous, axis=1)
            steps.append({"from": k - 1, "to": k, "meanFractionOfDiagonal": float(step.mean() / diag),
                          "maxFractionOfDiagonal": float(step.max() / diag)})
        previous = frame
    total = np.linalg.norm(previous - points, axis=1)
    info = {
        "description": ("creature: arm 0 up 75 deg, arm 2 down 55 deg, arm 3 swung 45 deg, drift "
                        "(0.12, 0.06, 0)" if motion == "limbs" else
                        "creature: arm 0 raised 100 deg (make_pairs creature_arm_up)")
                       + ", over frames 1..%d at equal time steps" % frames,
        "frames": frames,
        "vertices": int(len(points)),
        "firstFrameBoxDiagonal": diag,
        "steps": steps,
        "motionFirstToLast": {"meanFractionOfDiagonal": float(total.mean() / diag),
                              "maxFractionOfDiagonal": float(total.max() / diag)},
        "minDetDg": {"vertices": det_vertices, "grid": det_grid},
    }
    mp.write_atomic(os.path.join(out_dir, "sequence.json"), json.dumps(info, indent=2) + "\n")
    print("%d frames, %d vertices, motion per step mean %.1f%% of the diagonal, first to last "
          "%.1f%% (max %.1f%%), min det Dg %.3f, %.1fs"
          % (frames, len(points), 100 * np.mean([s["meanFractionOfDiagonal"] for s in steps]),
             100 * total.mean() / diag, 100 * total.max() / diag, min(det_vertices, det_grid),
             time.time() - t0))


if __name__ == "__main__":
    main()
