#!/usr/bin/env bash
# Configures and builds flexbody in build/ (Release). Executables land in build/bin/.
# Usage: build.sh [TARGET...]. Without targets: everything, with the tests and the Python package. With targets
# (the quick start: fbprep fbsim): only those, configured without the tests and the Python package, whose packages
# setup.sh --quick does not install.
# FLEXBODY_WITH_SLEPC=ON|OFF in the environment switches the slepc eigensolver backend (left as configured if unset).
set -euo pipefail
cd "$(dirname "$0")/.."
options=(-DCMAKE_BUILD_TYPE=Release)
if (($#)); then
  options+=(-DFLEXBODY_BUILD_TESTS=OFF -DFLEXBODY_BUILD_PYTHON=OFF)
else
  options+=(-DFLEXBODY_BUILD_TESTS=ON -DFLEXBODY_BUILD_PYTHON=ON)
fi
if [[ -n "${FLEXBODY_WITH_SLEPC:-}" ]]; then options+=("-DFLEXBODY_WITH_SLEPC=${FLEXBODY_WITH_SLEPC}"); fi
cmake -S . -B build "${options[@]}" > build-configure.log 2>&1 || { cat build-configure.log; exit 1; }
rm -f build-configure.log
if (($#)); then
  targets=()
  for t in "$@"; do targets+=(--target "$t"); done
  cmake --build build -j"$(nproc)" "${targets[@]}"
else
  cmake --build build -j"$(nproc)"
fi
