# run(COMMAND...): one step of a -P script, fatal with the script's RUN_WHAT
# ("install consumer", ...) and the command when it exits non-zero. One
# copy for run_consumer.cmake, run_sanitize.cmake and
# fortran/run_consumer_fortran.cmake.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${RUN_WHAT} failed at: ${ARGN}")
  endif()
endfunction()
