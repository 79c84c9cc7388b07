#!/usr/bin/env bash
# CLI tests of the option tables (CLI11): one help page per command with its grouped options and
# defaults, the closest spelling suggested for a mistyped option or command, --name=VALUE,
# repeated options, --source/--target as an alternative to the positional shapes, `--`.
# Usage: test_cli_options.sh VDB_MATCH ASSETS_DIR
set -uo pipefail

VDB_MATCH=${1:?usage: test_cli_options.sh VDB_MATCH ASSETS_DIR}
ASSETS=${2:?usage: test_cli_options.sh VDB_MATCH ASSETS_DIR}
SPHERE="$ASSETS/sphere.vdb"
ELLIPSOID="$ASSETS/ellipsoid.vdb"
SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-cli-options.XXXXXX")
trap 'rm -rf "$SCRATCH"' EXIT

source "$(dirname "$0")/common.sh"

# ---------------------------------------------------------------- help pages
check help-overview-texture 0 'texture PHI.vdb --source M1 -o OUTDIR' '' -- --help
check help-short 0 'Usage: vdb_match energy' '' -- energy -h
for command in match energy consistency slice texture apply; do
    check "help-$command" 0 "^Usage: vdb_match (\[match\] SOURCE|$command)" '' -- "$command" --help
    count=$((count + 1))
    "$VDB_MATCH" "$command" --help >"$SCRATCH/help" 2>&1
    # Every page: its options grouped ("Group:" lines), -h/--help, the exit codes.
    if grep -Eq '^[A-Z][A-Za-z ()]+:$' "$SCRATCH/help" && grep -q -- '-h, --help' "$SCRATCH/help" &&
        grep -q '^Exit codes' "$SCRATCH/help"; then
        echo "ok   help-$command-complete"
    else
        fail "help-$command-complete: no option groups, -h/--help or exit codes"
        sed 's/^/  /' "$SCRATCH/help" | head -20
    fi
done
# Options with their defaults, wrapped at 100 columns.
"$VDB_MATCH" match --help >"$SCRATCH/match-help"
count=$((count + 1))
if grep -q -- '--max-level L' "$SCRATCH/match-help" && grep -q -- '-o, --output OUTDIR\|--output, -o OUTDIR' "$SCRATCH/match-help" &&
    grep -q 'default 4.096 in 3D, 0.512 in 2D' "$SCRATCH/match-help" &&
    grep -q '^Descent:$' "$SCRATCH/match-help" && [ "$(awk '{ if (length > 100) n++ } END { print n + 0 }' "$SCRATCH/match-help")" -eq 0 ]; then
    echo "ok   help-match-options"
else
    fail "help-match-options: an option, a default or a group is missing, or a line is too long"
fi
check help-apply-directions 0 'What moves where' '' -- apply --help
check help-word 0 'Commands:' '' -- help
check version-in-command 0 '^vdb_match [0-9]+\.[0-9]+\.[0-9]+' '' -- energy "$SPHERE" "$ELLIPSOID" --version

# ---------------------------------------------------------------- suggestions (exit 1)
check suggest-option 1 '' "unknown option '--levle' \(did you mean --level\?\)" -- energy "$SPHERE" "$ELLIPSOID" --levle 4
check suggest-match-option 1 '' "unknown option '--max-levle' \(did you mean --max-level\?\)" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --max-levle 7
check suggest-with-value 1 '' "unknown option '--c-mathc' \(did you mean --c-match\?\)" -- "$SPHERE" "$ELLIPSOID" -o "$SCRATCH/o" --c-mathc=3
check suggest-command 1 '' "unknown command 'energi' \(did you mean energy\?" -- energi "$SPHERE" "$ELLIPSOID"
check suggest-command-2 1 '' "unknown command 'warp'" -- warp "$SPHERE" "$ELLIPSOID"
check no-suggestion 1 '' "unknown option '--zzzzzzzz' \(see vdb_match --help\)" -- energy "$SPHERE" "$ELLIPSOID" --zzzzzzzz
check option-of-other-command 1 '' "unknown option '--stride'" -- energy "$SPHERE" "$ELLIPSOID" --stride 2
check flag-given-a-value 1 '' '--quiet takes no value' -- energy "$SPHERE" "$ELLIPSOID" --quiet=maybe
check flag-value-missing 1 '' '--grid expects a value NAME' -- energy "$SPHERE" "$ELLIPSOID" --grid
# As before CLI11: an option that needs a value takes the next argument, whatever it looks like.
check value-looks-like-option 1 '' "--level expects an integer, got '--quiet'" -- energy "$SPHERE" "$ELLIPSOID" --level --quiet

# ---------------------------------------------------------------- spellings
check equals-form 0 'level 3' '' -- energy "$SPHERE" "$ELLIPSOID" --level=3 --quiet
check repeated-last-wins 0 'level 3' '' -- energy "$SPHERE" "$ELLIPSOID" --level 9 --level 3 --quiet
check source-target-options 0 'level 3' '' -- energy --source "$SPHERE" --target "$ELLIPSOID" --level 3 --quiet
check target-option-and-positional 0 'level 3' '' -- energy "$SPHERE" --target "$ELLIPSOID" --level 3 --quiet
check source-option-and-two-positionals 1 '' 'besides --source/--target' -- "$SPHERE" "$ELLIPSOID" --source "$SPHERE" -o "$SCRATCH/o"
check double-dash 0 'level 3' '' -- energy --level 3 --quiet -- "$SPHERE" "$ELLIPSOID"
check negative-value 3 '' 'c_mem must be finite and >= 0' -- energy "$SPHERE" "$ELLIPSOID" --c-mem -1 --quiet
check negative-equals 3 '' 'c_mem must be finite and >= 0' -- energy "$SPHERE" "$ELLIPSOID" --c-mem=-1e-3 --quiet
check match-short-output 0 'converged|not converged' '' -- match --source "$SPHERE" --target "$ELLIPSOID" -o "$SCRATCH/m" --levels 3..3 --quiet --no-inverse --no-jacobian

echo "$((count - failures))/$count passed"
[ "$failures" -eq 0 ]
