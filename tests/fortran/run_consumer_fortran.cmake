# Install this build into a scratch prefix, then build and run an outside
# Fortran project against it twice: with find_package(catchup COMPONENTS
# Fortran) -> catchup::catchup_fortran, and with plain
#   FC main.f90 $(pkg-config --cflags --libs catchup-fortran)
# Invoked by ctest: cmake -DBUILD_DIR= -DSRC= -DWORK= -DFC= -P this.
set(RUN_WHAT "Fortran install consumer")
include(${CMAKE_CURRENT_LIST_DIR}/../run_step.cmake)
set(PREFIX ${WORK}/prefix)
file(REMOVE_RECURSE ${WORK})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})

# 1. CMake package
run(${CMAKE_COMMAND} -S ${SRC} -B ${WORK}/cmake-build -DCMAKE_PREFIX_PATH=${PREFIX}
    -DCMAKE_Fortran_COMPILER=${FC})
run(${CMAKE_COMMAND} --build ${WORK}/cmake-build)
run(${WORK}/cmake-build/consumer_fortran)
if(EXISTS ${WORK}/cmake-build/consumer_fortran_h5)
  execute_process(COMMAND ${WORK}/cmake-build/consumer_fortran_h5
                  WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer_fortran_h5 failed")
  endif()
endif()

# 2. pkg-config, plain compiler driver
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} "${PREFIX}/lib/pkgconfig:${PREFIX}/lib/x86_64-linux-gnu/pkgconfig")
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs catchup-fortran
                OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config does not know catchup-fortran")
endif()
message(STATUS "pkg-config --cflags --libs catchup-fortran: ${flags}")
separate_arguments(flags UNIX_COMMAND "${flags}")
run(${FC} ${SRC}/main.f90 -o ${WORK}/consumer_fortran_pc ${flags})
file(GLOB libdirs LIST_DIRECTORIES true ${PREFIX}/lib ${PREFIX}/lib/x86_64-linux-gnu)
list(JOIN libdirs ":" rpath)
set(ENV{LD_LIBRARY_PATH} "${rpath}")
run(${WORK}/consumer_fortran_pc)
