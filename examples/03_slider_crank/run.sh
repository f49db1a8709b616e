#!/usr/bin/env bash
# Example 03: a slider-crank with a flexible rod. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1: 0.02 s of the run instead of 0.3 s, for the tests).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
end=()
[[ "${FLEXBODY_EXAMPLE_QUICK:-0}" == 1 ]] && end=(--end 0.02)
# The rod: its body spec (Craig-Bampton, an interface at each bore). The crank and the slider are rigid in the
# scene, so a coarse linear mesh and one mode will do: the scene uses only their mass properties.
"$build/bin/fbprep" "$here/rod.yaml" -o "$out/rod.fbh5" -q
"$build/bin/fbprep" "$here/crank.geo" --unit mm --order 1 --modes 1 -o "$out/crank.fbh5" -q
"$build/bin/fbprep" "$here/slider.geo" --unit mm --order 1 --modes 1 -o "$out/slider.fbh5" -q
cp "$here/slider_crank.yaml" "$out/slider_crank.yaml"
"$build/bin/fbsim" "$out/slider_crank.yaml" -o "$out/slider_crank" "${end[@]}"
MPLBACKEND=Agg /usr/bin/python3 "$here/plot.py" "$out/slider_crank" "$out/result.png"
