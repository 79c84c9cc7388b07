#!/usr/bin/env bash
# CLI tests of `vdb_match consistency` and `vdb_match slice`: the 2D figure pair matched both
# ways at coarse levels, the consistency figures as a table and as JSON (keys, finite, small,
# the measures against the exact inverse of phi), the slice EXR (channels via iinfo) and its PNG
# previews, and the error cases with their exit codes.
# Usage: test_cli_eval.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_eval.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_eval.sh VDB_MATCH ASSETS_DIR}
FIGURE_A="$ASSETS/figure_a.polyline"
FIGURE_B="$ASSETS/figure_b.polyline"
SPHERE="$ASSETS/sphere.vdb"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-eval.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT
PYTHON=/usr/bin/python3

source "$(dirname "$0")/common.sh"


# 1. The pair, both ways.
check match-ab 0 '' '' -- "$FIGURE_A" "$FIGURE_B" -o "$SCRATCH/ab" --levels 4..6 --quiet
check match-ba 0 '' '' -- "$FIGURE_B" "$FIGURE_A" -o "$SCRATCH/ba" --levels 4..6 --quiet
PHI="$SCRATCH/ab/deformation.vdb"
PSI="$SCRATCH/ba/deformation.vdb"

# 2. consistency: table and JSON.
check consistency-table 0 'psi\(phi\(x\)\) - x' '' -- consistency "$PHI" "$PSI" \
    --source "$FIGURE_A" --target "$FIGURE_B"
count=$((count + 1))
if grep -Fq 'phi^-1(phi(x)) - x' "$SCRATCH/out" && grep -Fq 'psi(y) - phi^-1(y)' "$SCRATCH/out" &&
    grep -Eq 'walks that failed .*: 0 of [0-9]+ \(round trip\)' "$SCRATCH/out"; then
    echo "ok   consistency-table-inverse"
else
    fail "consistency-table-inverse"
    cat "$SCRATCH/out"
fi
check consistency-json 0 '"psi_phi"' '' -- consistency "$PHI" "$PSI" \
    --source "$FIGURE_A" --target "$FIGURE_B" --json --threads 2
cp "$SCRATCH/out" "$SCRATCH/consistency.json"
count=$((count + 1))
if "$PYTHON" - "$SCRATCH/consistency.json" <<'PY'
import json, math, sys
r = json.load(open(sys.argv[1]))
assert r["dimension"] == 2, r["dimension"]
assert r["domain_size"] > 0
for key in ("psi_phi", "phi_psi"):
    for space in ("world", "relative"):
        for k in ("omega_l2", "omega_linf", "shape_mean", "shape_max"):
            v = r[key][space][k]
            assert isinstance(v, float) and math.isfinite(v) and v >= 0, (key, space, k, v)
    assert r[key]["omega_points"] > 1000
    assert r[key]["shape_vertices"] > 10
    rel = r[key]["relative"]
    assert rel["shape_mean"] < 0.05, (key, rel)
    assert rel["omega_l2"] < 0.05, (key, rel)
    assert abs(r[key]["world"]["shape_mean"] / r["domain_size"] - rel["shape_mean"]) < 1e-12
# Against the exact inverse phi^-1 of phi: the round trip is rounding error, psi's distance to
# phi^-1 is of the order of |psi o phi - Id| (the same error at other points).
rt = r["inverse_round_trip"]
for space in ("world", "relative"):
    for k in ("omega_l2", "omega_linf"):
        v = rt[space][k]
        assert isinstance(v, float) and math.isfinite(v) and v >= 0, ("round trip", space, k, v)
assert rt["omega_points"] == r["psi_phi"]["omega_points"], rt
assert rt["failures"] == 0, rt
assert rt["relative"]["omega_linf"] < 1e-9, rt
pv = r["psi_vs_inverse"]
for space in ("world", "relative"):
    for k in ("omega_l2", "omega_linf", "shape_mean", "shape_max"):
        v = pv[space][k]
        assert isinstance(v, float) and math.isfinite(v) and v >= 0, ("psi vs inverse", space, k, v)
assert pv["omega_points"] == r["phi_psi"]["omega_points"], pv
assert pv["shape_vertices"] == r["phi_psi"]["shape_vertices"], pv
assert pv["failures"] == 0, pv
assert 0 < pv["relative"]["shape_mean"] < 0.05, pv
assert pv["relative"]["omega_l2"] < 0.05, pv
assert abs(pv["world"]["shape_mean"] / r["domain_size"] - pv["relative"]["shape_mean"]) < 1e-12
for key in ("residual_phi", "residual_psi"):
    for space in ("world", "relative"):
        for k in ("mean", "max"):
            v = r[key][space][k]
            assert math.isfinite(v) and v >= 0, (key, k, v)
    assert r[key]["relative"]["mean"] < 0.02, (key, r[key])
for key in ("det_phi", "det_psi"):
    d = r[key]
    assert 0 < d["min"] <= 1 <= d["max"], d
    assert d["simplices"] > 0 and d["non_positive"] == 0, d
    assert d["threshold"] == 0.1
    assert 0 <= d["fraction_below_threshold"] <= 1
print("psi_phi relative:", r["psi_phi"]["relative"])
print("phi_psi relative:", r["phi_psi"]["relative"])
print("inverse_round_trip relative:", rt["relative"])
print("psi_vs_inverse relative:", pv["relative"])
print("residual_phi relative:", r["residual_phi"]["relative"])
print("det_phi:", r["det_phi"]["min"], r["det_phi"]["max"])
PY
then
    echo "ok   consistency-json-values"
else
    fail "consistency-json-values"
fi

# 3. slice: EXR channels and PNG previews.
check slice-2d 0 'slice\.exr' '' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B" \
    --inverse "$PSI" -o "$SCRATCH/slice.exr"
count=$((count + 1))
if iinfo -v "$SCRATCH/slice.exr" >"$SCRATCH/iinfo" 2>&1; then
    missing=""
    for ch in d1 d2 displacement det residual inverse_error; do
        grep -Eq "channel list:.*\b$ch\b" "$SCRATCH/iinfo" || missing="$missing $ch"
    done
    grep -q 'vdbmatch:units: "world"' "$SCRATCH/iinfo" || missing="$missing units"
    grep -q 'vdbmatch:axis: "z"' "$SCRATCH/iinfo" || missing="$missing axis"
    grep -q 'vdbmatch:command' "$SCRATCH/iinfo" || missing="$missing command"
    if [ -n "$missing" ]; then
        fail "slice-exr: missing$missing"
        cat "$SCRATCH/iinfo"
    else
        echo "ok   slice-exr"
    fi
else
    fail "slice-exr: iinfo failed"
    cat "$SCRATCH/iinfo"
fi
count=$((count + 1))
missing=""
for ch in d1 d2 displacement det residual inverse_error; do
    [ -s "$SCRATCH/slice.$ch.png" ] || missing="$missing $ch"
done
if [ -n "$missing" ]; then fail "slice-png: missing$missing"; else echo "ok   slice-png"; fi
check slice-no-inverse 0 '' '' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B" \
    -o "$SCRATCH/noinv.exr" --resolution 40 --quiet
count=$((count + 1))
if [ ! -e "$SCRATCH/noinv.inverse_error.png" ] && [ -s "$SCRATCH/noinv.residual.png" ] &&
    iinfo "$SCRATCH/noinv.exr" | grep -Eq '40 x +40'; then
    echo "ok   slice-no-inverse-outputs"
else
    fail "slice-no-inverse-outputs"
    iinfo "$SCRATCH/noinv.exr"
fi

# 4. Errors.
check consistency-missing-file 2 '' 'does not exist|cannot|not found|No such' -- consistency \
    "$SCRATCH/none.vdb" "$PSI" --source "$FIGURE_A" --target "$FIGURE_B"
check consistency-missing-shape 2 '' '' -- consistency "$PHI" "$PSI" \
    --source "$SCRATCH/none.polyline" --target "$FIGURE_B"
check consistency-no-shapes 1 '' '--source M1 --target M2' -- consistency "$PHI" "$PSI"
check consistency-one-file 1 '' 'PHI.vdb PSI.vdb' -- consistency "$PHI" --source "$FIGURE_A" \
    --target "$FIGURE_B"
check consistency-wrong-grid 3 '' '' -- consistency "$SPHERE" "$PSI" --source "$FIGURE_A" \
    --target "$FIGURE_B"
check consistency-dimension 3 '' '' -- consistency "$PHI" "$PSI" --source "$SPHERE" \
    --target "$SPHERE"
check consistency-bad-stride 1 '' 'stride' -- consistency "$PHI" "$PSI" --source "$FIGURE_A" \
    --target "$FIGURE_B" --stride 0
check slice-missing-output 1 '' 'OUT.exr' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B"
check slice-not-exr 1 '' '\.exr' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B" \
    -o "$SCRATCH/x.png"
check slice-bad-axis 1 '' 'axis' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B" \
    -o "$SCRATCH/x.exr" --axis w
check slice-both-positions 1 '' 'cannot be combined' -- slice "$PHI" --source "$FIGURE_A" \
    --target "$FIGURE_B" -o "$SCRATCH/x.exr" --position 0 --unit-position 0.5
check slice-2d-axis 3 '' 'own plane' -- slice "$PHI" --source "$FIGURE_A" --target "$FIGURE_B" \
    -o "$SCRATCH/x.exr" --axis x
check slice-missing-phi 2 '' '' -- slice "$SCRATCH/none.vdb" --source "$FIGURE_A" \
    --target "$FIGURE_B" -o "$SCRATCH/x.exr"
check slice-wrong-grid 3 '' '' -- slice "$SPHERE" --source "$FIGURE_A" --target "$FIGURE_B" \
    -o "$SCRATCH/x.exr"
check slice-dimension 3 '' '' -- slice "$PHI" --source "$SPHERE" --target "$SPHERE" \
    -o "$SCRATCH/x.exr"
check help-lists-eval 0 'consistency PHI.vdb PSI.vdb' '' -- --help

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
