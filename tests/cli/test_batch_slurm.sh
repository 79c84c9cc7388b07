#!/usr/bin/env bash
# `vdb_match batch --executor slurm` against a real Slurm: installs slurm-wlm and munge if they
# are missing (as root), starts munged, slurmctld and slurmd for a single-node cluster whose state
# lives in a scratch folder, runs a small batch through a job array (--wait), checks that its
# results equal the local executor's voxel for voxel, resubmits after a job's outputs were
# removed (only that task), and stops the daemons by their pids. Exits 77 (ctest: skipped) with
# the reason when the daemons cannot start here (not root, no packages, no munge).
# Usage: test_batch_slurm.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_batch_slurm.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_batch_slurm.sh VDB_MATCH ASSETS_DIR}
SKIP=77
skip() {
    echo "SKIP: $*"
    exit $SKIP
}

[ "$(id -u)" -eq 0 ] || skip "the single-node Slurm needs root to start munged and slurmd"
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null 2>&1 ||
        skip "could not install slurm-wlm and munge"
fi

SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-slurm.XXXXXX")
chmod 755 "$SCRATCH"
PIDS=()
cleanup() {
    for f in "$SCRATCH/slurmd.pid" "$SCRATCH/slurmctld.pid"; do
        [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null
    done
    [ -n "${MUNGE_PID:-}" ] && kill "$MUNGE_PID" 2>/dev/null
    sleep 1
    rm -rf "$SCRATCH"
}
trap cleanup EXIT

# munge: a key if there is none, and our own munged on a socket in the scratch folder.
if [ ! -s /etc/munge/munge.key ]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    chown munge:munge /etc/munge/munge.key 2>/dev/null
    chmod 400 /etc/munge/munge.key
fi
mkdir -p "$SCRATCH/munge"
chown munge:munge "$SCRATCH/munge" 2>/dev/null
SOCKET="$SCRATCH/munge/munge.socket"
su -s /bin/sh munge -c "/usr/sbin/munged --socket=$SOCKET --pid-file=$SCRATCH/munge/munged.pid --log-file=$SCRATCH/munge/munged.log --seed-file=$SCRATCH/munge/seed --force" ||
    skip "munged does not start"
for _ in $(seq 1 50); do [ -s "$SCRATCH/munge/munged.pid" ] && break; sleep 0.1; done
MUNGE_PID=$(cat "$SCRATCH/munge/munged.pid" 2>/dev/null)
munge -S "$SOCKET" -n | unmunge -S "$SOCKET" >/dev/null 2>&1 || skip "munge does not authenticate"

HOST=$(hostname -s)
CPUS=$(nproc)
MEM=$(($(free -m | awk '/^Mem:/ {print $2}') - 512))
mkdir -p "$SCRATCH/state" "$SCRATCH/spool"
cat >"$SCRATCH/slurm.conf" <<CONF
ClusterName=vdbmatchtest
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$SCRATCH/state
SlurmdSpoolDir=$SCRATCH/spool
SlurmctldPidFile=$SCRATCH/slurmctld.pid
SlurmdPidFile=$SCRATCH/slurmd.pid
SlurmctldLogFile=$SCRATCH/slurmctld.log
SlurmdLogFile=$SCRATCH/slurmd.log
NodeName=$HOST CPUs=$CPUS RealMemory=$MEM State=UNKNOWN
PartitionName=batch Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
echo "ConstrainCores=no" >"$SCRATCH/cgroup.conf"
export SLURM_CONF="$SCRATCH/slurm.conf"
slurmctld -f "$SLURM_CONF" || skip "slurmctld does not start ($(tail -1 "$SCRATCH/slurmctld.log" 2>/dev/null))"
slurmd -f "$SLURM_CONF" || skip "slurmd does not start ($(tail -1 "$SCRATCH/slurmd.log" 2>/dev/null))"
for _ in $(seq 1 100); do
    sinfo -h -o '%t' 2>/dev/null | grep -q idle && break
    sleep 0.2
done
sinfo -h -o '%t' | grep -q idle || skip "the node did not come up: $(sinfo 2>&1 | tail -1)"
echo "single-node Slurm up: $HOST, $CPUS CPUs, $MEM MB"

source "$(dirname "$0")/common.sh"
# ok NAME: records a passed check (common.sh has fail and the counters).
ok() {
    count=$((count + 1))
    echo "ok   $1"
}

S=$SCRATCH/shapes
mkdir -p "$S"
chmod 755 "$S"
cp "$ASSETS/figure_a.polyline" "$S/a.polyline"
cp "$ASSETS/figure_b.polyline" "$S/b.polyline"
awk '/^#/ || NF == 0 {print; next} {printf "%.6f %.6f\n", $1 * 1.08, $2 * 0.95}' "$S/a.polyline" >"$S/c.polyline"
awk '/^#/ || NF == 0 {print; next} {printf "%.6f %.6f\n", $1 * 0.93, $2 * 1.05}' "$S/b.polyline" >"$S/d.polyline"
SHAPES=("$S/a.polyline" "$S/b.polyline" "$S/c.polyline" "$S/d.polyline")

t0=$(date +%s.%N)
"$VDB_MATCH" batch --all-pairs "${SHAPES[@]}" -o "$SCRATCH/local" --quiet -- --levels 4..6 >/dev/null ||
    fail "local executor"
t1=$(date +%s.%N)
"$VDB_MATCH" batch --all-pairs "${SHAPES[@]}" -o "$SCRATCH/slurm" --executor slurm --wait \
    --array-throttle "$CPUS" -- --levels 4..6 >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
t2=$(date +%s.%N)
if [ $code -eq 0 ] && grep -q '6/6 done, 0 failed' "$SCRATCH/out"; then
    ok "slurm executor: 6 array tasks done (--wait)"
else
    fail "slurm executor: exit $code: $(cat "$SCRATCH/out" "$SCRATCH/err" | tail -5)"
    tail -5 "$SCRATCH/slurmctld.log" "$SCRATCH/slurmd.log"
fi
echo "wall: local $(echo "$t1 - $t0" | bc) s, slurm $(echo "$t2 - $t1" | bc) s"
grep -q '^#SBATCH --array=0,1,2,3,4,5%' "$SCRATCH/slurm/slurm/batch.sbatch" && ok "the array script lists the jobs" ||
    fail "array script: $(grep array "$SCRATCH/slurm/slurm/batch.sbatch")"
[ "$(wc -l <"$SCRATCH/slurm/jobs.txt")" -eq 6 ] && ok "jobs.txt: one line per job" || fail "jobs.txt"

PYTHON=/usr/bin/python3
result=$("$PYTHON" - "$SCRATCH/local" "$SCRATCH/slurm" <<'PY'
import json, sys, pyopenvdb as vdb
a, b = sys.argv[1], sys.argv[2]
jobs = [j["name"] for j in json.load(open(a + "/plan.json"))["jobs"]]
def values(p):
    return sorted((x["min"], x["value"]) for x in vdb.readAll(p)[0][0].citerOnValues())
bad = [j for j in jobs if values(f"{a}/jobs/{j}/deformation.vdb") != values(f"{b}/jobs/{j}/deformation.vdb")
       or json.load(open(f"{a}/jobs/{j}/report.json"))["result"]["energy"]
       != json.load(open(f"{b}/jobs/{j}/report.json"))["result"]["energy"]]
print("ok" if not bad and len(jobs) == 6 else f"differ: {bad}")
PY
)
[ "$result" = ok ] && ok "slurm results equal the local executor's, voxel for voxel" || fail "$result"

"$VDB_MATCH" batch status "$SCRATCH/slurm" >"$SCRATCH/out" 2>&1
grep -q '6 jobs: 6 done' "$SCRATCH/out" && ok "batch status of a slurm batch" || fail "status: $(cat "$SCRATCH/out")"
"$VDB_MATCH" batch collect "$SCRATCH/slurm" --quiet >"$SCRATCH/out" 2>&1 && cmp -s "$SCRATCH/slurm/distances.csv" <("$VDB_MATCH" batch collect "$SCRATCH/local" --quiet >/dev/null && cat "$SCRATCH/local/distances.csv") &&
    ok "collect: the same distances.csv as the local batch" || fail "collect: $(cat "$SCRATCH/out")"

"$PYTHON" -c "
import json, sys
s = json.load(open(sys.argv[1] + '/summary.json'))
sys.exit(0 if all(r['seconds'] > 0 and r['peakMemoryMB'] > 0 for r in s['results']) else 1)" "$SCRATCH/slurm" &&
    ok "collect: time and memory of each task from its report" || fail "slurm summary: no time or memory"

# Resubmission: only the job whose outputs are gone.
rm "$SCRATCH/slurm/jobs/b--c/deformation.vdb"
"$VDB_MATCH" batch --all-pairs "${SHAPES[@]}" -o "$SCRATCH/slurm" --executor slurm --wait -- --levels 4..6 >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
if [ $code -eq 0 ] && grep -q '^#SBATCH --array=3$' "$SCRATCH/slurm/slurm/batch.sbatch" && [ -s "$SCRATCH/slurm/jobs/b--c/deformation.vdb" ]; then
    ok "resubmission: one array task for the one job redone"
else
    fail "resubmission: exit $code, $(grep array "$SCRATCH/slurm/slurm/batch.sbatch"), $(cat "$SCRATCH/err" | tail -3)"
fi

# A warm-start sequence: a chain of array tasks (%1), each started from the one before, the
# same results as the local executor's chain.
for k in 1 2 3 4; do
    awk -v f="$k" '/^#/ || NF == 0 {print; next} {printf "%.6f %.6f\n", $1 * (1 + 0.04 * f), $2 * (1 - 0.02 * f)}' \
        "$S/a.polyline" >"$S/seq.000$k.polyline"
done
WARM_THREADS=()
[ "$CPUS" -lt 2 ] && WARM_THREADS=(--threads-per-job 1)
"$VDB_MATCH" batch --sequence "$S/seq.####.polyline" --frames 1-4 --warm-start -o "$SCRATCH/warm_local" --quiet -- --levels 4..6 >/dev/null ||
    fail "warm-start sequence, local"
"$VDB_MATCH" batch --sequence "$S/seq.####.polyline" --frames 1-4 --warm-start -o "$SCRATCH/warm_slurm" --executor slurm --wait \
    "${WARM_THREADS[@]}" -- --levels 4..6 >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
"$VDB_MATCH" batch status "$SCRATCH/warm_slurm" >/dev/null 2>&1
result=$("$PYTHON" - "$SCRATCH/warm_local" "$SCRATCH/warm_slurm" <<'PY'
import json, sys
a, b = sys.argv[1], sys.argv[2]
pa, pb = json.load(open(a + "/plan.json")), json.load(open(b + "/plan.json"))
problems = []
if [j["warmStarted"] for j in pb["jobs"]] != [False, True, True]:
    problems.append("warmStarted %s" % [j["warmStarted"] for j in pb["jobs"]])
for j in pa["jobs"]:
    ea = json.load(open(f"{a}/jobs/{j['name']}/report.json"))["result"]["energy"]
    eb = json.load(open(f"{b}/jobs/{j['name']}/report.json"))["result"]["energy"]
    if ea != eb: problems.append(f"{j['name']}: energy {ea} != {eb}")
print("ok" if not problems else "; ".join(problems))
PY
)
if [ $code -eq 0 ] && grep -q '^#SBATCH --array=0,1,2%1$' "$SCRATCH/warm_slurm/slurm/batch.sbatch" && [ "$result" = ok ]; then
    ok "warm-start sequence: a %1 chain, each task from the one before, the local chain's energies"
else
    fail "warm-start sequence on slurm: exit $code, $(grep array "$SCRATCH/warm_slurm/slurm/batch.sbatch"), $result, $(tail -3 "$SCRATCH/err")"
fi

# A Slurm that refuses: an impossible memory request.
"$VDB_MATCH" batch --all-pairs "$S/a.polyline" "$S/b.polyline" -o "$SCRATCH/refused" --executor slurm \
    --memory-per-task 100000000 -- --levels 4..5 >"$SCRATCH/out" 2>"$SCRATCH/err"
code=$?
[ $code -eq 2 ] && grep -q 'sbatch refused' "$SCRATCH/err" && ok "a refused submission: exit code 2 and sbatch's reason" ||
    fail "refused: exit $code $(cat "$SCRATCH/err")"

# With VDBMATCH_SLURM_BENCH=1: the overhead of the Slurm path on a realistic batch (the 6 pairs
# of the bundled 3D shapes at levels VDBMATCH_SLURM_BENCH_LEVELS, default 4..6), local then
# slurm, wall times and their ratio.
if [ "${VDBMATCH_SLURM_BENCH:-0}" = 1 ]; then
    LEVELS=${VDBMATCH_SLURM_BENCH_LEVELS:-4..6}
    B=("$ASSETS/starfish_a.vdb" "$ASSETS/starfish_b.vdb" "$ASSETS/sphere.vdb" "$ASSETS/ellipsoid.vdb")
    t0=$(date +%s.%N)
    "$VDB_MATCH" batch --all-pairs "${B[@]}" -o "$SCRATCH/bench_local" --quiet -- --levels "$LEVELS" >/dev/null
    t1=$(date +%s.%N)
    "$VDB_MATCH" batch --all-pairs "${B[@]}" -o "$SCRATCH/bench_slurm" --quiet --executor slurm --wait -- --levels "$LEVELS" >/dev/null
    t2=$(date +%s.%N)
    echo "bench: 6 pairs 3D $LEVELS: local $(echo "$t1 - $t0" | bc) s, slurm $(echo "$t2 - $t1" | bc) s, ratio $(echo "scale=3; ($t2 - $t1) / ($t1 - $t0)" | bc)"
fi

echo "$count checks passed, $failures failed"
[ "$failures" -eq 0 ]
