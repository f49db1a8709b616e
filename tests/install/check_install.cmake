# Installs flexbody into a scratch prefix, builds examples/05_cpp_runtime against it with find_package(flexbody)
# (as a user's project would), and runs it on the sample bracket. Called by CTest with -DBUILD_DIR, -DSOURCE_DIR,
# -DWORK_DIR and -DFBPREP.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "failed (${status}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/05_cpp_runtime -B ${WORK_DIR}/example -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/example)
run(${FBPREP} ${SOURCE_DIR}/meshes/bracket.yaml -o ${WORK_DIR}/bracket.fbh5 --modes 4 -q)
run(${WORK_DIR}/example/pendulum ${WORK_DIR}/bracket.fbh5 bore_1 bore_3)
if(NOT last_output MATCHES "energy [-0-9.e]+ J after [0-9]+ Newton iterations")
  message(FATAL_ERROR "the example's output is not what it should be:\n${last_output}")
endif()
message(STATUS "${last_output}")

# The Python package where cmake --install put it (<prefix>/lib/python3.X/dist-packages), as python3 would find it
# under the default prefix /usr/local; it reads the same body file and runs a scene of it.
if(PYTHON3 AND PYTHON_PACKAGE_DIR)
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${WORK_DIR}/prefix/${PYTHON_PACKAGE_DIR} PYTHONDONTWRITEBYTECODE=1
      ${PYTHON3} ${SOURCE_DIR}/tests/install/check_python_package.py ${WORK_DIR}/bracket.fbh5)
  if(NOT last_output MATCHES "^[0-9]+\\.[0-9]+\\.[0-9]+ 4 10")
    message(FATAL_ERROR "the installed Python package printed:\n${last_output}")
  endif()
  message(STATUS "installed Python package: ${last_output}")
endif()
