# cmake --install: headers, the libraries flexbody::format and flexbody::runtime with a CMake package
# (lib/cmake/flexbody), and the tools. A simulator's CMakeLists then needs only
#   find_package(flexbody REQUIRED)
#   target_link_libraries(my_simulator PRIVATE flexbody::runtime)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set_target_properties(flexbody_format PROPERTIES EXPORT_NAME format)
set_target_properties(flexbody_runtime PROPERTIES EXPORT_NAME runtime)
set_target_properties(flexbody_warnings PROPERTIES EXPORT_NAME warnings)  # a link-only interface of the static libs
install(TARGETS flexbody_format flexbody_runtime flexbody_warnings EXPORT flexbodyTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/formats/include/flexbody/format
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/flexbody FILES_MATCHING PATTERN "*.hpp" PATTERN "yaml_reader.hpp" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/runtime/include/flexbody/runtime DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/flexbody)
install(EXPORT flexbodyTargets NAMESPACE flexbody:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flexbody)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/flexbodyConfig.cmake.in
  ${PROJECT_BINARY_DIR}/flexbodyConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flexbody)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/flexbodyConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/flexbodyConfig.cmake ${PROJECT_BINARY_DIR}/flexbodyConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/FlexbodyKlu.cmake DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flexbody)
install(TARGETS fbsim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET fbprep)
  install(TARGETS fbprep RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
