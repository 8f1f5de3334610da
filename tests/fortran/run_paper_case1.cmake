# Run examples/fortran/paper_case1 and check its HDF5 file with h5ls:
# /t [N] and /x [N, 3] with N = n + 1. Invoked by ctest:
#   cmake -DEXE= -DH5LS= -DOUT= -DN= -P run_paper_case1.cmake
file(REMOVE ${OUT})
execute_process(COMMAND ${EXE} ${N} ${OUT} RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message("${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "x\\(T\\) =")
  message(FATAL_ERROR "paper_case1 failed (${rc})")
endif()
execute_process(COMMAND ${H5LS} -r ${OUT} RESULT_VARIABLE rc OUTPUT_VARIABLE ls)
message("${ls}")
math(EXPR rows "${N} + 1")
if(NOT rc EQUAL 0 OR NOT ls MATCHES "/t +Dataset {${rows}(/[A-Za-z0-9]+)?}"
   OR NOT ls MATCHES "/x +Dataset {${rows}(/[A-Za-z0-9]+)?, 3(/[A-Za-z0-9]+)?}")
  message(FATAL_ERROR "${OUT} does not hold /t [${rows}] and /x [${rows}, 3]")
endif()
