#!/usr/bin/env bash
# Installs the packages, builds vdbmatch (Release) and matches the bundled example pairs:
#   3D: assets/starfish_a.vdb -> assets/starfish_b.vdb (levels 4..8)  -> out/starfish/
#   2D: assets/figure_a.polyline -> assets/figure_b.polyline (levels 4..9) -> out/figure/
# Each output directory holds deformation.vdb, deformed.vdb, deformed.obj and report.json
# (docs/cli.md). Options after the script name are passed to both runs, e.g. --levels 4..6.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
VDB_MATCH=./build/tools/vdb_match/vdb_match
"$VDB_MATCH" assets/starfish_a.vdb assets/starfish_b.vdb -o out/starfish "$@"
"$VDB_MATCH" assets/figure_a.polyline assets/figure_b.polyline -o out/figure "$@"
echo "example: outputs in out/starfish and out/figure (report.json: per-level figures and residuals)"
