#!/usr/bin/env bash
# Regenerates bracket.step and bracket.brep from bracket.geo with gmsh (OpenCASCADE writes the STEP
# file in mm, as the .geo is; BREP carries no unit). gmsh 4.8 cannot write IGES.
set -euo pipefail
cd "$(dirname "$0")"
gmsh bracket.geo -0 -format step -o bracket.step > /dev/null
gmsh bracket.geo -0 -o bracket.brep > /dev/null
echo "wrote $(pwd)/bracket.step and bracket.brep"
