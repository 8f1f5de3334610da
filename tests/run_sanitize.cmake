# Configure, build and run the unit and stress tests with -fsanitize=address,undefined.
# Invoked by ctest as: cmake -DSRC=... -DBIN=... -P run_sanitize.cmake
set(RUN_WHAT "sanitizer run")
include(${CMAKE_CURRENT_LIST_DIR}/run_step.cmake)
run(${CMAKE_COMMAND} -S ${SRC} -B ${BIN} -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Debug -DCATCHUP_SANITIZE=ON -DCATCHUP_WERROR=ON
    -DCATCHUP_BUILD_APPS=OFF -DCATCHUP_BUILD_FORTRAN=OFF)
run(${CMAKE_COMMAND} --build ${BIN} --parallel 2)
set(ENV{ASAN_OPTIONS} "detect_leaks=1:abort_on_error=0:halt_on_error=1")
set(ENV{UBSAN_OPTIONS} "print_stacktrace=1:halt_on_error=1")
# the unit tests and the stress tests (those without the apps; the known
# issue is left out: its expected failure would hide a sanitizer report)
run(${CMAKE_CTEST_COMMAND} --test-dir ${BIN} -L "unit|stress" -LE "valgrind" --output-on-failure)
