#!/usr/bin/env bash
# Example 05: the runtime linked into your own C++ program. Usage: run.sh BUILD_DIR OUT_DIR
# Installs flexbody from BUILD_DIR into OUT_DIR/prefix, builds pendulum.cpp against it with find_package(flexbody),
# runs it on the bracket (fbprep ../../meshes/bracket.yaml) and plots the printed path. The test suite runs the same
# steps (tests/install/check_install.cmake), so FLEXBODY_EXAMPLE_QUICK changes nothing here: the run takes seconds.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "$1" && pwd)"
mkdir -p "$2"
out="$(cd "$2" && pwd)"
cmake --install "$build" --prefix "$out/prefix" > /dev/null
cmake -S "$here" -B "$out/example" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$out/prefix" > /dev/null
cmake --build "$out/example" > /dev/null
"$build/bin/fbprep" "$here/../../meshes/bracket.yaml" -o "$out/bracket.fbh5" --modes 6 -q
"$out/example/pendulum" "$out/bracket.fbh5" bore_1 bore_3 | tee "$out/pendulum.txt"
grep -v '^energy' "$out/pendulum.txt" > "$out/path.csv"
MPLBACKEND=Agg /usr/bin/python3 "$here/plot.py" "$out/path.csv" "$out/result.png"
