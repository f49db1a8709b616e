#!/usr/bin/env bash
# Example 02: a body spec with Craig-Bampton interfaces and an output region. Usage: run.sh BUILD_DIR OUT_DIR
# (FLEXBODY_EXAMPLE_QUICK=1: 2 ms of the bolted bracket instead of 10 ms, for the tests).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
end=()
[[ "${FLEXBODY_EXAMPLE_QUICK:-0}" == 1 ]] && end=(--end 0.002)
"$build/bin/fbprep" "$here/bracket_cb.yaml" -o "$out/bracket_cb.fbh5"
cp "$here/bolted.yaml" "$out/bolted.yaml"
"$build/bin/fbsim" "$out/bolted.yaml" -o "$out/bolted" "${end[@]}"
MPLBACKEND=Agg /usr/bin/python3 "$here/plot.py" "$out/bracket_cb.fbh5" "$out/bolted" "$out/result.png"
