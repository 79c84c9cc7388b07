#!/usr/bin/env bash
# `cmake --install` puts the library, vdb_match and the Python package where they work from the
# install tree alone (relative RUNPATHs): installs into a temporary prefix, then matches a 2D
# pair with the installed module and runs the installed command.
# Usage: test_install.sh BUILD_DIR PYTHON ASSETS_DIR PYTHON_INSTALL_DIR
set -euo pipefail
build=$1 python=$2 assets=$3 pydir=$4
prefix=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-install-test.XXXXXX")
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build" --prefix "$prefix" >/dev/null
"$prefix/bin/vdb_match" --version
cd "$prefix"  # not the source tree: the installed package must be the one imported
PYTHONPATH="$prefix/$pydir" "$python" - "$assets" "$prefix" <<'PY'
import os, sys
import vdbmatch
assets, prefix = sys.argv[1], sys.argv[2]
assert vdbmatch.__file__.startswith(prefix), vdbmatch.__file__
r = vdbmatch.match(os.path.join(assets, "figure_a.polyline"), os.path.join(assets, "figure_b.polyline"),
                   levels="4..5", progress=False)
assert r.report["status"] == "converged", r.report["status"]
print("installed module:", vdbmatch.__file__, r)
PY
