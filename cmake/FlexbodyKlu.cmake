# SuiteSparse's KLU, the sparse LU of the runtime's reduced Newton matrix for scenes of many bodies
# (runtime/src/integrator/reduced_solver.hpp). SuiteSparse 5.x on Debian ships no CMake config; its headers live in
# /usr/include/suitesparse. Included by the build and by the installed flexbodyConfig.cmake (flexbody::runtime is a
# static library, so what links it links KLU too).
if(NOT TARGET SuiteSparse::KLU)
  find_path(KLU_INCLUDE_DIR klu.h PATH_SUFFIXES suitesparse REQUIRED)
  find_library(KLU_LIBRARY NAMES klu REQUIRED)
  add_library(SuiteSparse::KLU UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::KLU PROPERTIES IMPORTED_LOCATION ${KLU_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES ${KLU_INCLUDE_DIR})
endif()
