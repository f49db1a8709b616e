#!/usr/bin/env bash
# Example 01: the bracket pendulum from the command line. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1: 0.05 s of swing instead of 1 s, for the tests).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
end=()
[[ "${FLEXBODY_EXAMPLE_QUICK:-0}" == 1 ]] && end=(--end 0.05)
"$build/bin/fbprep" "$here/../../meshes/bracket.yaml" -o "$out/bracket.fbh5" -q
cp "$here/scene.yaml" "$out/scene.yaml"
"$build/bin/fbsim" "$out/scene.yaml" -o "$out/run" "${end[@]}"
MPLBACKEND=Agg /usr/bin/python3 "$here/plot.py" "$out/run" "$out/result.png"
