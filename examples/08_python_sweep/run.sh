#!/usr/bin/env bash
# Example 08: a step-size sweep from Python. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1: 0.08 s of swing instead of 0.4 s, for the tests).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
end=0.4
[[ "${FLEXBODY_EXAMPLE_QUICK:-0}" == 1 ]] && end=0.08
"$build/bin/fbprep" "$here/../../meshes/bracket.yaml" -o "$out/bracket.fbh5" -q
MPLBACKEND=Agg PYTHONPATH="$build/python" /usr/bin/python3 "$here/sweep.py" "$out/bracket.fbh5" "$out/result.png" "$end"
