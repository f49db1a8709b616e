#!/usr/bin/env bash
# Example 06: the bracket's body file read from Python with h5py. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1 changes nothing: there is no simulation to shorten).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
"$build/bin/fbprep" "$here/../../meshes/bracket.yaml" -o "$out/bracket.fbh5" -q
MPLBACKEND=Agg /usr/bin/python3 "$here/read_body.py" "$out/bracket.fbh5" "$out/result.png"
