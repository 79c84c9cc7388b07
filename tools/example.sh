#!/usr/bin/env bash
# Installs the packages, builds vdbmatch (Release) and runs vdb_match on the bundled example:
# the energy terms of the identity deformation between assets/sphere.vdb and assets/ellipsoid.vdb.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh
./build/tools/vdb_match/vdb_match energy assets/sphere.vdb assets/ellipsoid.vdb --level 6
