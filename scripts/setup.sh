#!/usr/bin/env bash
# Installs what flexbody needs on Debian 12, and nothing twice: packages already present are skipped.
# Run as root (or with sudo). Idempotent: a second run installs nothing. Usage: setup.sh [--with-slepc | --quick]
set -euo pipefail

# What fbprep and fbsim need (the quick start, --quick).
packages=(
  build-essential cmake pkg-config
  libeigen3-dev          # dense and sparse linear algebra everywhere
  libhdf5-dev            # the body file (*.fbh5)
  libgmsh-dev            # CAD import (OpenCASCADE: STEP/IGES/BREP) and tetrahedral meshing
  libsuitesparse-dev     # CHOLMOD: the sparse Cholesky factorization behind shift-invert
  libarpack2-dev         # ARPACK: the default eigensolver
  libspectra-dev         # Spectra: the second eigensolver backend
  libopenblas0-pthread   # optimized BLAS: CHOLMOD is ~10x slower on Debian's reference BLAS
  libblas-dev            # cblas.h: dense products on the BLAS (block Lanczos, GCMS constants); OpenBLAS at run time
  libcli11-dev           # fbprep's command line
  libyaml-cpp-dev        # body specs (fbprep body.yaml) and fbsim scenes
  libfmt-dev             # formatting of reports and messages
  nlohmann-json3-dev     # --json output
)
# Everything else: the tests, the Python package, the benchmarks and the examples.
full=(
  git
  clang-format           # scripts/check_format.sh: the layout of changed C++ lines (a test)
  gmsh                   # the gmsh command (meshes/make_bracket_cad.sh, looking at meshes)
  libgtest-dev           # the test suite
  calculix-ccx           # independent FE code the tests compare against
  pybind11-dev python3-dev python3-numpy   # the Python package flexbody (python/)
  python3-pytest                    # its tests
  python3-matplotlib python3-h5py   # benchmark plots (bench/ only), the Python examples
  freecad-common gmsh-doc           # public CAD parts for the corpus test and bench (FreeCAD's Idf models, gmsh's demos)
)
# --with-slepc: also what the optional slepc eigensolver backend needs (-DFLEXBODY_WITH_SLEPC=ON); the test
# suite builds it. PETSc brings Open MPI (mpirun) and MUMPS. --quick: only fbprep's and fbsim's.
case "${1:-}" in
  "") packages+=("${full[@]}") ;;
  --with-slepc) packages+=("${full[@]}" libslepc-real-dev libpetsc-real-dev) ;;
  --quick) ;;
  *) echo "setup: unknown option '$1' (--with-slepc or --quick)" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all packages present"
fi
