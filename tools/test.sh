#!/usr/bin/env bash
# Installs the packages, builds, and runs the test suite. By default the fast suite
# (ctest -LE slow); pass --all to include the convergence studies labelled "slow".
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
bash tools/build.sh -DVDBMATCH_WARNINGS_AS_ERRORS=ON
LABELS=(-LE slow)
if [ "${1:-}" = "--all" ]; then LABELS=(); fi
cd build
ctest --output-on-failure -j"$(nproc)" "${LABELS[@]}"
