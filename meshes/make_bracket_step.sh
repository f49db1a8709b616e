#!/usr/bin/env bash
# Regenerates bracket.step from bracket.geo with gmsh (OpenCASCADE writes STEP in mm, as the .geo is).
set -euo pipefail
cd "$(dirname "$0")"
gmsh bracket.geo -0 -format step -o bracket.step > /dev/null
echo "wrote $(pwd)/bracket.step"
