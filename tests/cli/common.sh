# Shared by the CLI test scripts (sourced): counters, fail, and check.
# The caller sets VDB_MATCH and SCRATCH first.

failures=0
count=0

# fail MESSAGE: records a failed check.
fail() {
    failures=$((failures + 1))
    echo "FAIL $1"
}

# check NAME EXPECTED_CODE STDOUT_PATTERN STDERR_PATTERN -- ARGS...
# Runs vdb_match ARGS. Patterns are extended regular expressions ('' = no check). A command
# failing with a code other than 5 (interrupted) must print exactly one line on stderr, starting
# with "vdb_match: error: ".
check() {
    local name=$1 expected=$2 outPattern=$3 errPattern=$4
    shift 5
    count=$((count + 1))
    "$VDB_MATCH" "$@" >"$SCRATCH/out" 2>"$SCRATCH/err"
    local code=$?
    local problem=""
    if [ "$code" -ne "$expected" ]; then
        problem="exit code $code, expected $expected"
    elif [ -n "$outPattern" ] && ! grep -Eq -- "$outPattern" "$SCRATCH/out"; then
        problem="stdout does not match /$outPattern/"
    elif [ -n "$errPattern" ] && ! grep -Eq -- "$errPattern" "$SCRATCH/err"; then
        problem="stderr does not match /$errPattern/"
    elif [ "$expected" -ne 0 ] && [ "$expected" -ne 5 ]; then
        if [ "$(wc -l <"$SCRATCH/err")" -ne 1 ] || ! grep -q '^vdb_match: error: ' "$SCRATCH/err"; then
            problem="stderr is not one 'vdb_match: error: ' line"
        fi
    fi
    if [ -n "$problem" ]; then
        fail "$name: $problem"
        echo "  command: vdb_match $*"
        sed 's/^/  stdout: /' "$SCRATCH/out" | head -20
        sed 's/^/  stderr: /' "$SCRATCH/err" | tail -20
    else
        echo "ok   $name"
    fi
}

# find_python MODULES: sets PYTHON to the first of $VDBMATCH_PYTHON, /usr/bin/python3 and python3
# that can import MODULES (e.g. "pyopenvdb, numpy"); exits with a "FAIL setup" line if none can.
find_python() {
    PYTHON=""
    local candidate
    for candidate in "${VDBMATCH_PYTHON:-}" /usr/bin/python3 python3; do
        if [ -n "$candidate" ] && "$candidate" -c "import $1" >/dev/null 2>&1; then
            PYTHON=$candidate
            return 0
        fi
    done
    echo "FAIL setup: no python with $1 (set VDBMATCH_PYTHON)"
    exit 1
}
