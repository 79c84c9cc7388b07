#!/usr/bin/env python3
"""Does a 2D match keep the inner distance to the nearest limb end, as the known map g does?
(issue: correspondence; docs/results.md, "The inner distance to the nearest extremity").

    inner_distance.py --pair PAIRDIR --run LABEL=FORWARD_DIR [--run ...] [--pixel 0.004]
                      [--radius 15 --radius 30] [--ratio 1 --ratio 1.5 ...]

PAIRDIR is a 2D pair of bench/accuracy/make_pairs.py (source.polyline, target_resampled.polyline,
truth.xyz); FORWARD_DIR a vdb_match match output of it (deformed.obj, and report.json with the
placement and the automatic landmarks' extremity pairs, `autoLandmarks.pairs`).

F1(x) is the inner distance of x in M1 to the nearest of M1's paired extremities, F2 the same in M2
with the paired points: the length of the shortest path inside the shape, on a pixel graph of
--pixel world units with 16 neighbours (Euclidean edge lengths; paths about 1-2% longer than the
true ones), read at a boundary point as the least F(pixel) + |point - pixel| over the inner
pixels of the 5 x 5 block around it (wider where it has none). An articulation keeps F on a limb
(the path from the limb's end runs along the limb); a slide of the skin along the limb changes it
by the slide. Prints, per run, in 10^-3 of the unit box (the match's placement, as score.py):

    LABEL PAIR err E motion M  moving g A phi B  all g C phi D  oracle@R X ...

err and motion as score.py; "moving" the mean of |F2(g(v)) - F1(v)| (g) and |F2(phi(v)) - F1(v)|
(phi) over the vertices g moves by more than 5 x 10^-3 of the box, "all" over every vertex; and
for each --radius R (10^-3 of the box) the error of an oracle of a term that would move phi(v)
along M2 to keep F: among the points of M2 (its vertices and three points per edge) within R of
phi(v), the one whose F2 is closest to F1(v).

With --ratio R, also the distance to each point's *own* extremity, as the inner-distance term
of vdb_match keeps it (docs/numerics.md, "The inner distance"): F1,k and F2,k from each paired
extremity k alone, k the one nearest to v in M1, over the vertices whose second-nearest
extremity is at least R times as far (`--inner-distance-ratio`; 1: every vertex):

    ... own@R share S g A phi B

S the percentage of M1's vertices kept, A and B the means of |F2,k(g(v)) - F1,k(v)| and
|F2,k(phi(v)) - F1,k(v)| over them. Exit status 2 for bad usage or unreadable input.
"""

import argparse
import heapq
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from score import read_points, read_run  # noqa: E402

MOVING = 5e-3  # |g(v) - v| above which a vertex is moving (box units), as score.py
OFFSETS = [(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 2), (2, -1), (1, -2)]


def fail(message):
    print("inner_distance.py: " + message, file=sys.stderr)
    sys.exit(2)


def read_curves(path):
    """The closed curves of a vdbmatch polyline (blank lines separate curves)."""
    curves, current = [], []
    with open(path) as f:
        for line in f:
            s = line.strip()
            if s.startswith("#"):
                continue
            if not s:
                if current:
                    curves.append(np.array(current))
                current = []
                continue
            current.append([float(t) for t in s.split()[:2]])
    if current:
        curves.append(np.array(current))
    if not curves or any(len(c) < 3 for c in curves):
        raise ValueError("%s: expected closed curves of at least 3 points" % path)
    return curves


class InnerDistance:
    """Inner distance to the nearest of `sources` in the shape bounded by `curves` (even-odd),
    on a pixel grid of `pixel` world units covering [lo, hi]."""

    def __init__(self, curves, sources, lo, hi, pixel):
        from matplotlib.path import Path
        self.lo, self.pixel = np.asarray(lo, float), pixel
        nx = int(np.ceil((hi[0] - lo[0]) / pixel)) + 1
        ny = int(np.ceil((hi[1] - lo[1]) / pixel)) + 1
        i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        centres = self.lo + pixel * np.c_[i.ravel(), j.ravel()]
        inside = np.zeros(len(centres), bool)
        for c in curves:
            inside ^= Path(c).contains_points(centres)
        inside = inside.reshape(nx, ny)
        dist = np.full((nx, ny), np.inf)
        heap = []
        for s in sources:
            k = self._nearest_inside(inside, np.asarray(s, float)[:2])
            if k is None:
                raise ValueError("extremity %s has no inner pixel near it" % (list(s),))
            d0 = float(np.linalg.norm(self.lo + pixel * np.array(k) - np.asarray(s)[:2]))
            if d0 < dist[k]:
                dist[k] = d0
                heapq.heappush(heap, (d0, k))
        steps = [(di * sx, dj * sy, pixel * np.hypot(di, dj)) for di, dj in OFFSETS
                 for sx, sy in ((1, 1), (-1, -1))]
        while heap:
            d, (a, b) = heapq.heappop(heap)
            if d > dist[a, b]:
                continue
            for di, dj, w in steps:
                p, q = a + di, b + dj
                if 0 <= p < nx and 0 <= q < ny and inside[p, q] and d + w < dist[p, q]:
                    dist[p, q] = d + w
                    heapq.heappush(heap, (d + w, (p, q)))
        self.dist = dist

    def _nearest_inside(self, inside, point):
        c = np.rint((point - self.lo) / self.pixel).astype(int)
        best = None
        for r in range(1, 6):
            for a in range(c[0] - r, c[0] + r + 1):
                for b in range(c[1] - r, c[1] + r + 1):
                    if 0 <= a < inside.shape[0] and 0 <= b < inside.shape[1] and inside[a, b]:
                        d = np.hypot(*(self.lo + self.pixel * np.array([a, b]) - point))
                        if best is None or d < best[0]:
                            best = (d, (a, b))
            if best is not None:
                return best[1]
        return None

    def __call__(self, points):
        """F at `points` (world units): least F(pixel) + |point - pixel| over the 5 x 5 block
        around each point, or a wider block (up to 17 x 17) where that has no inner pixel."""
        points = np.asarray(points, float)
        best = np.full(len(points), np.inf)
        for reach in (2, 4, 8):
            todo = np.flatnonzero(~np.isfinite(best))
            if len(todo) == 0:
                break
            p = points[todo]
            c = np.rint((p - self.lo) / self.pixel).astype(int)
            b_todo = best[todo]
            for da in range(-reach, reach + 1):
                for db in range(-reach, reach + 1):
                    a = np.clip(c[:, 0] + da, 0, self.dist.shape[0] - 1)
                    b = np.clip(c[:, 1] + db, 0, self.dist.shape[1] - 1)
                    centre = self.lo + self.pixel * np.c_[a, b]
                    b_todo = np.minimum(b_todo, self.dist[a, b] +
                                        np.linalg.norm(p - centre, axis=1))
            best[todo] = b_todo
        return best


def edge_points(curves, per_edge=4):
    pts = []
    for c in curves:
        nxt = np.roll(c, -1, axis=0)
        for t in np.arange(per_edge) / per_edge:
            pts.append(c + t * (nxt - c))
    return np.vstack(pts)


def oracle(phi, f1, candidates, f_candidates, radius):
    """Per vertex, the candidate within `radius` of phi(v) whose F2 is closest to F1(v)."""
    out = np.empty_like(phi)
    for start in range(0, len(phi), 256):
        p = phi[start:start + 256]
        d = np.linalg.norm(p[:, None, :] - candidates[None, :, :], axis=2)
        cost = np.abs(f_candidates[None, :] - f1[start:start + 256, None])
        cost[d > radius] = np.inf
        nearest = np.argmin(d, axis=1)
        pick = np.argmin(cost, axis=1)
        none = ~np.isfinite(cost[np.arange(len(p)), pick])
        pick[none] = nearest[none]
        out[start:start + 256] = candidates[pick]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", required=True)
    ap.add_argument("--run", action="append", required=True, metavar="LABEL=FORWARD_DIR")
    ap.add_argument("--pixel", type=float, default=0.004, help="world units (default 0.004)")
    ap.add_argument("--ratio", type=float, action="append", default=[],
                    help="also the distance to each point's own extremity, over the points whose "
                         "second-nearest extremity is at least R times as far (>= 1)")
    ap.add_argument("--radius", type=float, action="append",
                    help="oracle radius, 10^-3 of the box (default 15 and 30)")
    a = ap.parse_args(argv)
    radii = a.radius or [15.0, 30.0]
    if a.pixel <= 0 or any(r <= 0 for r in radii):
        fail("--pixel and --radius must be > 0")
    if any(not (r >= 1) for r in a.ratio):
        fail("--ratio must be >= 1")
    try:
        pair = json.load(open(os.path.join(a.pair, "pair.json")))
        if pair.get("dimension") != 2:
            fail("%s is not a 2D pair" % pair.get("name", a.pair))
        src = read_curves(os.path.join(a.pair, "source.polyline"))
        tgt = read_curves(os.path.join(a.pair, "target_resampled.polyline"))
        verts = np.vstack(src)
        truth = read_points(os.path.join(a.pair, "truth.xyz"), 2)
        if len(truth) != len(verts):
            fail("truth.xyz has %d points, the source %d" % (len(truth), len(verts)))
        runs = []
        for spec in a.run:
            label, d, report, phi = read_run(spec, 2)
            if len(phi) != len(verts):
                fail("%s: %d vertices, the source has %d" % (d, len(phi), len(verts)))
            pairs = (report.get("autoLandmarks") or {}).get("pairs") or []
            if not pairs:
                fail("%s: no paired extremities in report.json (autoLandmarks.pairs)" % d)
            runs.append((label, phi, report["placement"]["scale"], pairs))
    except (OSError, ValueError, KeyError) as e:
        fail(str(e))

    everything = np.vstack([verts, np.vstack(tgt), truth] + [r[1] for r in runs])
    lo, hi = everything.min(0) - 10 * a.pixel, everything.max(0) + 10 * a.pixel
    candidates = edge_points(tgt)
    cache = {}
    for label, phi, scale, pairs in runs:
        key = json.dumps(pairs)
        if key not in cache:
            try:
                f1 = InnerDistance(src, [p["source"] for p in pairs], lo, hi, a.pixel)
                f2 = InnerDistance(tgt, [p["target"] for p in pairs], lo, hi, a.pixel)
            except ValueError as e:
                fail(str(e))
            own = None
            if a.ratio:
                try:
                    f1k = np.array([InnerDistance(src, [p["source"]], lo, hi, a.pixel)(verts)
                                    for p in pairs])
                    f2k = [InnerDistance(tgt, [p["target"]], lo, hi, a.pixel) for p in pairs]
                except ValueError as e:
                    fail(str(e))
                own = (f1k, f2k, np.array([f(truth) for f in f2k]))
            cache[key] = (f1(verts), f2, f2(truth), f2(candidates), own)
        f1v, f2, f2g, f2c, own = cache[key]
        k = 1e3 * scale
        motion = np.linalg.norm(truth - verts, axis=1) * scale
        moving = motion > MOVING
        dg = np.abs(f2g - f1v) * k
        dp = np.abs(f2(phi) - f1v) * k
        err = np.linalg.norm(phi - truth, axis=1) * k
        mean = (lambda x, m: float(x[m].mean()) if m.any() else float("nan"))
        line = "%s %s err %.4g motion %.4g  moving g %.4g phi %.4g  all g %.4g phi %.4g" % (
            label, pair["name"], err.mean(), motion.mean() * 1e3, mean(dg, moving),
            mean(dp, moving), dg.mean(), dp.mean())
        for r in radii:
            o = oracle(phi, f1v, candidates, f2c, r / k)
            line += "  oracle@%g %.4g" % (r, np.linalg.norm(o - truth, axis=1).mean() * k)
        if own is not None:
            f1k, f2k, f2kg = own
            nearest = f1k.argmin(0)
            ordered = np.sort(f1k, 0)
            second = ordered[1] if len(f1k) > 1 else np.full(len(verts), np.inf)
            i = np.arange(len(verts))
            mine = f1k[nearest, i]
            dg = np.abs(f2kg[nearest, i] - mine) * k
            f2kp = np.array([f(phi) for f in f2k])
            dp = np.abs(f2kp[nearest, i] - mine) * k
            for r in a.ratio:
                kept = second >= r * mine
                line += "  own@%g share %.4g g %.4g phi %.4g" % (
                    r, 100 * kept.mean(), mean(dg, kept), mean(dp, kept))
        print(line)


if __name__ == "__main__":
    main()
