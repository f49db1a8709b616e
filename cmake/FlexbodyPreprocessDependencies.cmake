# Dependencies of fbprep. gmsh, CHOLMOD and ARPACK ship no CMake config on Debian 12, so they are
# found here by header and library (ARPACK through its arpack.pc) and wrapped in imported targets.
find_package(PkgConfig REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)

# Spectra 1.0 (header only; Debian installs no config file for it).
find_path(SPECTRA_INCLUDE_DIR Spectra/SymGEigsShiftSolver.h REQUIRED)
add_library(flexbody_spectra INTERFACE)
add_library(Spectra::Spectra ALIAS flexbody_spectra)
target_include_directories(flexbody_spectra SYSTEM INTERFACE ${SPECTRA_INCLUDE_DIR})

# gmsh 4.8 C++ API (libgmsh-dev).
find_path(GMSH_INCLUDE_DIR gmsh.h REQUIRED)
find_library(GMSH_LIBRARY NAMES gmsh REQUIRED)
add_library(Gmsh::gmsh UNKNOWN IMPORTED)
set_target_properties(Gmsh::gmsh PROPERTIES IMPORTED_LOCATION ${GMSH_LIBRARY}
  INTERFACE_INCLUDE_DIRECTORIES ${GMSH_INCLUDE_DIR})

# CHOLMOD (SuiteSparse 5.x); headers live in /usr/include/suitesparse on Debian.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY NAMES cholmod REQUIRED)
find_library(SUITESPARSECONFIG_LIBRARY NAMES suitesparseconfig REQUIRED)
add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
set_target_properties(SuiteSparse::CHOLMOD PROPERTIES IMPORTED_LOCATION ${CHOLMOD_LIBRARY}
  INTERFACE_INCLUDE_DIRECTORIES ${CHOLMOD_INCLUDE_DIR}
  INTERFACE_LINK_LIBRARIES ${SUITESPARSECONFIG_LIBRARY})

# The BLAS's C interface (cblas.h from libblas-dev) for the block-lanczos backend's dense products. Debian links
# against the reference libblas.so; at run time the libblas.so.3 alternative is OpenBLAS (libopenblas0-pthread).
find_package(BLAS REQUIRED)
find_path(CBLAS_INCLUDE_DIR cblas.h REQUIRED)

# ARPACK (arpack-ng 3.8) through pkg-config.
pkg_check_modules(ARPACK REQUIRED IMPORTED_TARGET arpack)
add_library(ARPACK::ARPACK ALIAS PkgConfig::ARPACK)

# The optional slepc eigensolver backend (fbprep --eigensolver slepc, under mpirun): SLEPc 3.18 and PETSc with
# MUMPS, from Debian's libslepc-real-dev and libpetsc-real-dev (they bring Open MPI). Off by default: the
# packages are large, and one process with CHOLMOD is faster on one machine (bench/README.md).
option(FLEXBODY_WITH_SLEPC "Build the distributed slepc eigensolver backend (needs SLEPc, PETSc with MUMPS, MPI)" OFF)
if(FLEXBODY_WITH_SLEPC)
  pkg_check_modules(SLEPC REQUIRED IMPORTED_TARGET slepc)
  find_package(MPI REQUIRED COMPONENTS C)  # also MPIEXEC_EXECUTABLE and MPIEXEC_NUMPROC_FLAG for the tests
endif()
