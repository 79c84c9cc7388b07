#!/usr/bin/env bash
# Installs the packages, builds vdbmatch (Release) and matches the bundled example pairs:
#   3D: assets/starfish_a.vdb -> assets/starfish_b.vdb (levels 4..8)  -> out/starfish/
#   2D: assets/figure_a.polyline -> assets/figure_b.polyline (levels 4..9) -> out/figure/
# Each output directory holds deformation.vdb, inverse.vdb, jacobian.vdb, deformed.vdb,
# deformed.obj and report.json (docs/cli.md); then `apply` carries the 2D target back onto the
# source space by the exact inverse (docs/apply.md). Options after the script name are passed to
# both matches, e.g. --levels 4..6.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
VDB_MATCH=./build/tools/vdb_match/vdb_match
"$VDB_MATCH" assets/starfish_a.vdb assets/starfish_b.vdb -o out/starfish "$@"
"$VDB_MATCH" assets/figure_a.polyline assets/figure_b.polyline -o out/figure "$@"
# M2 pulled back by phi^-1: it lies on M1 up to the matching residual.
"$VDB_MATCH" apply out/figure/deformation.vdb assets/figure_b.polyline --inverse \
    -o out/figure/target_on_source.polyline
echo "example: outputs in out/starfish and out/figure (report.json: per-level figures and residuals)"
