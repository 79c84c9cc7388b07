#!/usr/bin/env bash
# `cmake --install` puts the library, vdb_match and the Python package where they work from the
# install tree alone (relative RUNPATHs): installs into a temporary prefix, then matches a 2D
# pair with the installed module and runs the installed command, which writes pictures through
# the installed OpenImageIO module (libvdbmatch_image.so, loaded on first use: the library itself
# does not link OpenImageIO).
# Usage: test_install.sh BUILD_DIR PYTHON ASSETS_DIR PYTHON_INSTALL_DIR
set -euo pipefail
build=$1 python=$2 assets=$3 pydir=$4
prefix=$(mktemp -d "${TMPDIR:-/tmp}/vdbmatch-install-test.XXXXXX")
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build" --prefix "$prefix" >/dev/null
"$prefix/bin/vdb_match" --version
lib=$(dirname "$(find "$prefix" -name 'libvdbmatch.so' | head -1)")
test -f "$lib/libvdbmatch_image.so" || { echo "libvdbmatch_image.so is not installed next to libvdbmatch.so"; exit 1; }
if readelf -d "$lib/libvdbmatch.so" | grep -q 'OpenImageIO'; then
    echo "libvdbmatch.so links OpenImageIO; it should load it as a module"; exit 1
fi
"$prefix/bin/vdb_match" "$assets/figure_a.polyline" "$assets/figure_b.polyline" -o "$prefix/out" \
    --levels 4..5 --quiet
"$prefix/bin/vdb_match" slice "$prefix/out/deformation.vdb" --source "$assets/figure_a.polyline" \
    --target "$assets/figure_b.polyline" -o "$prefix/out/slice.exr" >/dev/null
test -s "$prefix/out/slice.exr" && test -s "$prefix/out/slice.det.png"
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
