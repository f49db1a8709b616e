#!/usr/bin/env bash
# Quick start: installs what is missing, builds, and runs fbprep on the bundled bracket (a STEP file
# in mm), printing its report. The body file lands in build/bracket.fbh5.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
build/bin/fbprep meshes/bracket.yaml -o build/bracket.fbh5
