# Install this build into a scratch prefix, then build and run an outside
# project against it twice: once with find_package(catchup), once with
# pkg-config only.
set(RUN_WHAT "install consumer")
include(${CMAKE_CURRENT_LIST_DIR}/run_step.cmake)
set(PREFIX ${WORK}/prefix)
file(REMOVE_RECURSE ${WORK})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})

# 1. CMake package
run(${CMAKE_COMMAND} -S ${SRC} -B ${WORK}/cmake-build
    -DCMAKE_PREFIX_PATH=${PREFIX})
run(${CMAKE_COMMAND} --build ${WORK}/cmake-build)
run(${WORK}/cmake-build/consumer_shared)
run(${WORK}/cmake-build/consumer_static)
if(EXISTS ${WORK}/cmake-build/consumer_h5)
  run(${WORK}/cmake-build/consumer_h5 ${WORK})
endif()

# 2. pkg-config, plain cc
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} "${PREFIX}/lib/pkgconfig:${PREFIX}/lib/x86_64-linux-gnu/pkgconfig")
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs catchup
                OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config does not know catchup")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
file(GLOB libdirs LIST_DIRECTORIES true ${PREFIX}/lib ${PREFIX}/lib/x86_64-linux-gnu)
run(cc ${SRC}/main.c -o ${WORK}/consumer_pc ${flags})
list(JOIN libdirs ":" rpath)
set(ENV{LD_LIBRARY_PATH} "${rpath}")
run(${WORK}/consumer_pc)
