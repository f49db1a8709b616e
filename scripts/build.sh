#!/usr/bin/env bash
# Configures and builds flexbody in build/ (Release). Executables land in build/bin/.
# FLEXBODY_WITH_SLEPC=ON|OFF in the environment switches the slepc eigensolver backend (left as configured if unset).
set -euo pipefail
cd "$(dirname "$0")/.."
options=(-DCMAKE_BUILD_TYPE=Release)
if [[ -n "${FLEXBODY_WITH_SLEPC:-}" ]]; then options+=("-DFLEXBODY_WITH_SLEPC=${FLEXBODY_WITH_SLEPC}"); fi
cmake -S . -B build "${options[@]}" > build-configure.log 2>&1 || { cat build-configure.log; exit 1; }
rm -f build-configure.log
cmake --build build -j"$(nproc)"
