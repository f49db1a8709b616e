#!/usr/bin/env bash
# Example 04: a spinning part with geometric stiffening. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1: 0.02 s of the spin-up instead of 3 s, for the tests).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
end=()
[[ "${FLEXBODY_EXAMPLE_QUICK:-0}" == 1 ]] && end=(--end 0.02)
"$build/bin/fbprep" "$here/beam.yaml" -o "$out/beam.fbh5" -q
cp "$here/spin.yaml" "$out/spin.yaml"
"$build/bin/fbsim" "$out/spin.yaml" -o "$out/spin" "${end[@]}"
MPLBACKEND=Agg /usr/bin/python3 "$here/plot.py" "$out/beam.fbh5" "$out/spin" "$out/result.png"
