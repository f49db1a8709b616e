# Warnings for the project's own targets (not for third-party headers).
add_library(flexbody_warnings INTERFACE)
target_compile_options(flexbody_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor>)
