#!/usr/bin/env bash
# Installs what is missing, builds (with the optional slepc backend, so its tests run on one and on two
# MPI ranks), and runs the whole test suite (GoogleTest through CTest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --with-slepc
FLEXBODY_WITH_SLEPC=ON bash scripts/build.sh
# The CalculiX comparisons fail instead of skipping when ccx is missing.
FLEXBODY_REQUIRE_CCX=1 ctest --test-dir build --output-on-failure -j"$(nproc)"
