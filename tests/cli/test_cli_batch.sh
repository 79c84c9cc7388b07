#!/usr/bin/env bash
# CLI tests of `vdb_match batch`: plans (all pairs, template, sequence), plan.json states, resume
# (finished jobs skipped, a job with missing outputs redone), a failing job that does not stop
# the others (exit code 6), an interrupted batch (exit code 5, jobs redone on resume), bad input
# (missing frame, duplicated names, another plan in OUTDIR, options batch sets itself), status,
# and collect (distances.csv, summary.json with |psi o phi - Id| where both directions ran).
# Usage: test_cli_batch.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_batch.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_batch.sh VDB_MATCH ASSETS_DIR}
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-batch.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"
find_python "json"

# expect NAME CONDITION...: a check on the state left behind.
expect() {
    local name=$1
    shift
    count=$((count + 1))
    if "$@"; then echo "ok   $name"; else fail "$name"; fi
}
# state DIR JOB: the job's state in DIR/plan.json.
state() {
    "$PYTHON" -c "import json,sys; p=json.load(open(sys.argv[1]+'/plan.json')); print([j['state'] for j in p['jobs'] if j['name']==sys.argv[2]][0])" "$1" "$2"
}

S=$SCRATCH/shapes
mkdir -p "$S"
cp "$ASSETS/figure_a.polyline" "$S/a.polyline"
cp "$ASSETS/figure_b.polyline" "$S/b.polyline"
awk '/^#/ || NF == 0 {print; next} {printf "%.6f %.6f\n", $1 * 1.08, $2 * 0.95}' "$S/a.polyline" >"$S/c.polyline"
LEVELS=(-- --levels 4..5)

# All pairs, then the same command again: nothing to do.
check "all pairs: 3 jobs done" 0 '3/3 done, 0 failed' 'a--b done' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" "$S/c.polyline" -o "$SCRATCH/pairs" "${LEVELS[@]}"
expect "all pairs: each job is a match folder" test -s "$SCRATCH/pairs/jobs/b--c/deformation.vdb" -a -s "$SCRATCH/pairs/jobs/b--c/report.json"
expect "all pairs: plan.json says done" [ "$(state "$SCRATCH/pairs" a--c)" = done ]
check "resume: finished jobs skipped" 0 '3/3 done' '3 jobs \(3 already done\)' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" "$S/c.polyline" -o "$SCRATCH/pairs" "${LEVELS[@]}"
rm "$SCRATCH/pairs/jobs/a--c/deformation.vdb"
check "resume: a job whose outputs are not whole is redone" 0 '3/3 done' '\(2 already done\)' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" "$S/c.polyline" -o "$SCRATCH/pairs" "${LEVELS[@]}"
expect "resume: that job, and only it, ran again" grep -q 'batch: a--c done' "$SCRATCH/err"
expect "resume: its outputs are back" test -s "$SCRATCH/pairs/jobs/a--c/deformation.vdb"
check "another plan in the same OUTDIR is refused" 1 '' 'holds another batch' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" -o "$SCRATCH/pairs" "${LEVELS[@]}"
check "status" 0 '3 jobs: 3 done, 0 failed' '' -- batch status "$SCRATCH/pairs"

# Collect: a symmetric matrix with zeros on the diagonal, and the summary.
check "collect" 0 'distances.csv' '' -- batch collect "$SCRATCH/pairs"
count=$((count + 1))
result=$("$PYTHON" - "$SCRATCH/pairs" <<'PY'
import csv, json, sys
d = sys.argv[1]
rows = list(csv.reader(open(d + "/distances.csv")))
names = rows[0][1:]
m = {r[0]: dict(zip(names, map(float, r[1:]))) for r in rows[1:]}
s = json.load(open(d + "/summary.json"))
e = {r["name"]: r["energy"] for r in s["results"]}
ok = names == ["a", "b", "c"] and all(m[x][x] == 0 for x in names)
ok = ok and all(m[x][y] == m[y][x] > 0 for x in names for y in names if x != y)
# (distances.csv has 6 significant digits: at most half a unit of the sixth, 5e-6 relative)
ok = ok and abs(m["a"]["b"] - e["a--b"] ** 0.5) <= 5.01e-6 * m["a"]["b"] and s["done"] == 3
ok = ok and s["pictures"]["clusterOrder"] and sorted(s["pictures"]["clusterOrder"]) == names
# each job's residuals, both ways, as its report has them
for r in s["results"]:
    rep = json.load(open(d + "/jobs/" + r["name"] + "/report.json"))["result"]
    ok = ok and r["residual"] == rep["residual"] and r["targetResidual"] == rep["targetResidual"]
    rep = json.load(open(d + "/jobs/" + r["name"] + "/report.json"))
    ok = ok and r["smallPieces"] == {"source": rep["source"]["smallPieces"], "target": rep["target"]["smallPieces"]}
    ok = ok and r["smallPieces"]["source"]["count"] == 0
print("ok" if ok else f"bad matrix or summary: {m} {e}")
PY
)
[ "$result" = ok ] && echo "ok   collect: distances.csv symmetric, sqrt of the energies of summary.json" || fail "collect: $result"
expect "collect: heat map and MDS pictures" test -s "$SCRATCH/pairs/distances.png" -a -s "$SCRATCH/pairs/mds.png"

# A job that fails (a shape the reader refuses) does not stop the others: exit code 6.
printf '# one point\n1 2\n' >"$S/bad.polyline"
count=$((count + 1))
"$VDB_MATCH" batch --template "$S/a.polyline" "$S/b.polyline" "$S/bad.polyline" -o "$SCRATCH/tpl" --quiet "${LEVELS[@]}" >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
if [ $code -eq 6 ] && grep -q 'failed: a--bad: readPolyline' "$SCRATCH/out" && [ "$(state "$SCRATCH/tpl" a--b)" = done ] \
    && [ "$(state "$SCRATCH/tpl" a--bad)" = failed ]; then
    echo "ok   a failing job: exit code 6, listed with its error, the others done"
else
    fail "a failing job: exit code $code; $(cat "$SCRATCH/out" "$SCRATCH/err")"
fi

# Sequences: Blender's #### and Houdini's \$F4; a missing frame is an I/O error.
mkdir -p "$SCRATCH/seq"
for k in 1 2 3; do cp "$S/a.polyline" "$SCRATCH/seq/shape.000$k.polyline"; done
check "sequence ####: frame k -> k+1" 0 '2/2 done' 'shape.0002--shape.0003 done' -- \
    batch --sequence "$SCRATCH/seq/shape.####.polyline" --frames 1-3 -o "$SCRATCH/seqout" "${LEVELS[@]}"
check "sequence \$F4 names the same frames" 0 '2/2 done' '' -- \
    batch --sequence "$SCRATCH/seq/shape.\$F4.polyline" --frames 1-3 -o "$SCRATCH/seqout" "${LEVELS[@]}"
check "sequence: a missing frame" 2 '' 'frame 4 of the sequence is missing' -- \
    batch --sequence "$SCRATCH/seq/shape.####.polyline" --frames 1-4 -o "$SCRATCH/seq2" "${LEVELS[@]}"
expect "sequence: nothing written for a refused plan" test ! -e "$SCRATCH/seq2/plan.json"

# A sequence's collect: the first frame's curve carried to every frame, and the composed maps.
mkdir -p "$SCRATCH/morph"
"$PYTHON" - "$S/a.polyline" "$S/b.polyline" "$SCRATCH/morph" <<'PY'
import sys
def read(p):
    return [[float(v) for v in l.split()] for l in open(p) if l.strip() and not l.startswith("#")]
a, b = read(sys.argv[1]), read(sys.argv[2])
for k in range(4):
    t = k / 3
    with open(f"{sys.argv[3]}/fig.{k + 1:04d}.polyline", "w") as f:
        f.writelines(f"{(1 - t) * p[0] + t * q[0]:.6f} {(1 - t) * p[1] + t * q[1]:.6f}\n" for p, q in zip(a, b))
PY
check "sequence of a morph" 0 '3/3 done' '' -- \
    batch --sequence "$SCRATCH/morph/fig.####.polyline" --frames 1-4 -o "$SCRATCH/morphout" --quiet -- --levels 4..6
check "sequence collect" 0 '3 of 3 jobs done' '' -- batch collect "$SCRATCH/morphout" --quiet
# The same chain by hand: frame 1's curve through the three jobs' deformations with apply.
cp "$SCRATCH/morph/fig.0001.polyline" "$SCRATCH/chain0.polyline"
for k in 1 2 3; do
    "$VDB_MATCH" apply "$SCRATCH/morphout/jobs/fig.000$k--fig.000$((k + 1))/deformation.vdb" \
        "$SCRATCH/chain$((k - 1)).polyline" -o "$SCRATCH/chain$k.polyline" >/dev/null 2>&1
done
count=$((count + 1))
result=$("$PYTHON" - "$SCRATCH" <<'PY'
import sys
d = sys.argv[1]
def obj(p):
    return [[float(x) for x in l.split()[1:3]] for l in open(p) if l.startswith("v ")]
def poly(p):
    return [[float(v) for v in l.split()] for l in open(p) if l.strip() and not l.startswith("#")]
seq = obj(d + "/morphout/sequence/deformed.0004.obj")
chain = poly(d + "/chain3.polyline")
first = obj(d + "/morphout/sequence/deformed.0001.obj")
src = poly(d + "/morph/fig.0001.polyline")
err = max(abs(a - b) for p, q in zip(seq, chain) for a, b in zip(p, q))
err1 = max(abs(a - b) for p, q in zip(first, src) for a, b in zip(p, q))
moved = max(abs(a - b) for p, q in zip(seq, src) for a, b in zip(p, q))
ok = len(seq) == len(chain) == len(src) and err < 1e-5 and err1 < 1e-6 and moved > 0.05
print("ok" if ok else f"sequence mesh: {len(seq)} {len(chain)} err {err} first {err1} moved {moved}")
PY
)
[ "$result" = ok ] && echo "ok   sequence: deformed.0004.obj is frame 1 carried by the three maps" || fail "$result"
expect "sequence: composed maps 2..4" test -s "$SCRATCH/morphout/sequence/composed.0004.vdb" -a -s "$SCRATCH/morphout/sequence/composed.0002.vdb"
if "$PYTHON" -c "import pyopenvdb, numpy" 2>/dev/null; then
    count=$((count + 1))
    result=$("$PYTHON" - "$SCRATCH/morphout" <<'PY'
import sys, pyopenvdb as vdb
d = sys.argv[1]
def values(p):
    g = vdb.readAll(p)[0][0]
    return {x["min"]: x["value"] for x in g.citerOnValues()}
first = values(d + "/jobs/fig.0001--fig.0002/deformation.vdb")
composed = values(d + "/sequence/composed.0002.vdb")
err = max(max(abs(a - b) for a, b in zip(first[c], composed[c])) for c in first)
print("ok" if first.keys() == composed.keys() and err < 1e-6 else f"composed.0002 differs from phi_0 by {err}")
PY
)
    [ "$result" = ok ] && echo "ok   sequence: composed.0002.vdb is the first map" || fail "$result"
fi

# Warm starts along the sequence: one chain, job k started from job k-1's map (match
# --warm-start), recorded in plan.json, the reports and jobs.txt; resume keeps the chain.
check "sequence --warm-start" 0 '3/3 done' '' -- \
    batch --sequence "$SCRATCH/morph/fig.####.polyline" --frames 1-4 --warm-start -o "$SCRATCH/warmout" --quiet -- --levels 4..6
count=$((count + 1))
result=$("$PYTHON" - "$SCRATCH/warmout" <<'PY'
import json, sys
d = sys.argv[1]
p = json.load(open(d + "/plan.json"))
jobs = p["jobs"]
problems = []
if p.get("warmStart") is not True: problems.append("plan.warmStart")
if [j["warmStartFrom"] for j in jobs] != [None, 0, 1]: problems.append("warmStartFrom %s" % [j["warmStartFrom"] for j in jobs])
if [j["warmStarted"] for j in jobs] != [False, True, True]: problems.append("warmStarted")
for k, j in enumerate(jobs):
    r = json.load(open(d + "/jobs/" + j["name"] + "/report.json"))
    if k == 0 and r["init"] is not None: problems.append("job 0 init")
    if k > 0:
        i = r["init"] or {}
        if i.get("kind") != "warm-start" or not i.get("path", "").endswith(jobs[k - 1]["name"] + "/deformation.vdb") or [l["level"] for l in r["levels"]] != [5, 6]:
            problems.append("job %d report init %s levels %s" % (k, i, [l["level"] for l in r["levels"]]))
lines = open(d + "/jobs.txt").read().splitlines()
if "--warm-start" in lines[0] or "if [ -s " not in lines[1] or "--warm-start" not in lines[2]: problems.append("jobs.txt")
print("ok" if not problems else "; ".join(problems))
PY
)
[ "$result" = ok ] && echo "ok   sequence --warm-start: a chain in plan.json, the reports and jobs.txt" || fail "$result"
# jobs.txt's line of a warm job runs from the identity when its predecessor left no map.
cp -r "$SCRATCH/warmout" "$SCRATCH/warmcopy"
rm "$SCRATCH/warmcopy/jobs/fig.0001--fig.0002/deformation.vdb"
sed -n 2p "$SCRATCH/warmout/jobs.txt" | sed "s#$SCRATCH/warmout#$SCRATCH/warmcopy#g" >"$SCRATCH/line2.sh"
count=$((count + 1))
if bash "$SCRATCH/line2.sh" && "$PYTHON" -c "
import json, sys
r = json.load(open(sys.argv[1]))
sys.exit(0 if r['init'] is None and [l['level'] for l in r['levels']] == [4, 5, 6] else 1)" \
    "$SCRATCH/warmcopy/jobs/fig.0002--fig.0003/report.json"; then
    echo "ok   jobs.txt: a warm job without its predecessor's map runs from the identity"
else
    fail "jobs.txt warm line without the predecessor's map"
fi
check "warm-start status" 0 'fig.0002--fig.0003  done .*\(warm start\)' '' -- batch status "$SCRATCH/warmout"
check "warm-start collect" 0 '3 of 3 jobs done' '' -- batch collect "$SCRATCH/warmout" --quiet
expect "warm-start: the sequence collected" test -s "$SCRATCH/warmout/sequence/deformed.0004.obj"
check "warm-start is another plan" 1 '' 'holds another batch' -- \
    batch --sequence "$SCRATCH/morph/fig.####.polyline" --frames 1-4 -o "$SCRATCH/warmout" --quiet -- --levels 4..6
check "warm-start goes with --sequence" 1 '' '--warm-start goes with --sequence' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" --warm-start -o "$SCRATCH/w2"
check "--warm-start after -- is batch's" 1 '' "'--warm-start' after -- is set by batch" -- \
    batch --sequence "$SCRATCH/morph/fig.####.polyline" --frames 1-4 -o "$SCRATCH/w3" -- --warm-start x.vdb

# Usage errors.
mkdir -p "$SCRATCH/dup"
cp "$S/a.polyline" "$SCRATCH/dup/a.polyline"
check "duplicated names" 1 '' 'duplicated names' -- \
    batch --all-pairs "$S/a.polyline" "$SCRATCH/dup/a.polyline" -o "$SCRATCH/d"
check "no plan" 1 '' 'exactly one of' -- batch "$S/a.polyline" -o "$SCRATCH/d"
check "-o after -- is batch's" 1 '' 'set by batch' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" -o "$SCRATCH/d" -- -o x
check "a missing shape" 2 '' 'cannot read the shape' -- \
    batch --all-pairs "$S/a.polyline" "$S/nothere.polyline" -o "$SCRATCH/d"
check "status of a folder without a batch" 2 '' 'no plan.json' -- batch status "$SCRATCH"
check "an unwritable OUTDIR" 2 '' 'output directory' -- \
    batch --all-pairs "$S/a.polyline" "$S/b.polyline" -o /proc/vdbmatch-batch-test
# A Slurm that is not there: no sbatch on the PATH.
count=$((count + 1))
env PATH=/nonexistent "$VDB_MATCH" batch --all-pairs "$S/a.polyline" "$S/b.polyline" -o "$SCRATCH/noslurm" \
    --executor slurm "${LEVELS[@]}" >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
if [ $code -eq 2 ] && grep -q 'sbatch is not installed' "$SCRATCH/err" && [ "$(state "$SCRATCH/noslurm" a--b)" = pending ]; then
    echo "ok   no Slurm: exit code 2, the reason, nothing marked done"
else
    fail "no Slurm: exit $code: $(cat "$SCRATCH/err")"
fi

# Ctrl-C: the running jobs stop, the batch exits 5, and the same command redoes them.
"$VDB_MATCH" batch --all-pairs "$ASSETS/sphere.vdb" "$ASSETS/ellipsoid.vdb" --both-directions \
    -o "$SCRATCH/int" --quiet -- --levels 4..6 >"$SCRATCH/out" 2>"$SCRATCH/err" &
pid=$!
for _ in $(seq 1 100); do
    [ -s "$SCRATCH/int/jobs/sphere--ellipsoid/log.txt" ] || [ -d "$SCRATCH/int/jobs/sphere--ellipsoid" ] && break
    sleep 0.1
done
sleep 1
kill -INT $pid
wait $pid
code=$?
count=$((count + 1))
st=$(state "$SCRATCH/int" sphere--ellipsoid)
if [ $code -eq 5 ] && [ "$st" = interrupted ]; then echo "ok   interrupted: exit code 5, jobs marked interrupted"; else fail "interrupted: exit $code, state $st"; fi
check "interrupted jobs are redone" 0 '2/2 done' '\(0 already done\)' -- \
    batch --all-pairs "$ASSETS/sphere.vdb" "$ASSETS/ellipsoid.vdb" --both-directions -o "$SCRATCH/int" -- --levels 4..6
check "collect with both directions" 0 '2 of 2 jobs done' '' -- batch collect "$SCRATCH/int"
count=$((count + 1))
result=$("$PYTHON" -c "
import json,sys
s=json.load(open(sys.argv[1]+'/summary.json'))
v=[r['psiPhiMinusId']['relative']['shape_mean'] for r in s['results']]
print('ok' if all(0 < x < 0.02 for x in v) else v)" "$SCRATCH/int")
[ "$result" = ok ] && echo "ok   collect: |psi o phi - Id| of both directions" || fail "collect consistency: $result"

echo "$((count - failures))/$count batch checks passed"
[ "$failures" -eq 0 ]
