# cmake -DCOMMAND=<list> -DEXPECTED_EXIT=<code> -DEXPECTED_OUTPUT=<text> -P check_run.cmake
# Runs COMMAND and fails unless its exit code is EXPECTED_EXIT and its stdout or stderr contains EXPECTED_OUTPUT.
# (PASS_REGULAR_EXPRESSION alone would ignore the exit code, and mpirun's exit code is the first failing rank's.)
execute_process(COMMAND ${COMMAND} RESULT_VARIABLE exit_code OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(FIND "${out}${err}" "${EXPECTED_OUTPUT}" found)
if(NOT exit_code STREQUAL "${EXPECTED_EXIT}" OR found EQUAL -1)
  message(FATAL_ERROR "exit code ${exit_code} (expected ${EXPECTED_EXIT}); expected to find: ${EXPECTED_OUTPUT}\n"
                      "stdout:\n${out}\nstderr:\n${err}")
endif()
