#!/usr/bin/env bash
# Quick start: installs what fbprep and fbsim need, builds only those two, runs fbprep on the bundled bracket (a STEP
# file in mm), printing its report, then fbsim on a scene that swings the bracket from one bore (a flexible pendulum).
# The body file lands in build/bracket.fbh5, the scene's CSV files in build/bracket_pendulum/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --quick
bash scripts/build.sh fbprep fbsim
build/bin/fbprep meshes/bracket.yaml -o build/bracket.fbh5
build/bin/fbsim meshes/bracket_pendulum.yaml -o build/bracket_pendulum
