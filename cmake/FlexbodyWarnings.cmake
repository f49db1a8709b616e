# Warnings for the project's own targets (not for third-party headers).
add_library(flexbody_warnings INTERFACE)
target_compile_options(flexbody_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor>)
# GCC 12's own AVX-512 intrinsics headers trip -W(maybe-)uninitialized (GCC bug 105593) wherever Eigen uses them:
# with FLEXBODY_NATIVE on such a machine every file would warn about a line in the compiler's headers.
if(FLEXBODY_NATIVE AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(flexbody_warnings INTERFACE -Wno-maybe-uninitialized -Wno-uninitialized)
endif()
