# catchup_h5: the HDF5 run writer (src/h5/h5run*.c, include/catchup/h5run.h)
# and the helpers every HDF5 writer shares (h5util.c: the sweep's results
# file uses them too, through catchup_h5_static).
# Included from src/CMakeLists.txt only when CATCHUP_BUILD_APPS is ON, since
# HDF5 (and MPI, which the parallel HDF5 headers include) are found only then.
#
# HDF5 and MPI are PRIVATE: h5run.h does not include hdf5.h, so a consumer of
# the shared catchup::catchup_h5 needs neither at build time (the dynamic
# linker finds them through the library's DT_NEEDED entries).
#
# Compiled once (hidden but for CUP_API, as libcatchup) into the shared
# library and into catchup_h5_static, an internal archive over catchup_static
# for programs that also call the library's internal functions (catchup-sweep):
# linking the shared catchup_h5 would load a second copy of libcatchup there.
#
# util/fail.c (the error message into errmsg) is compiled in too: libcatchup
# hides its own copy. In catchup_h5_static the two archives' fail.o are the
# same object, so a program takes whichever it meets first.
add_library(catchup_h5_objects OBJECT ${CMAKE_CURRENT_LIST_DIR}/h5run.c ${CMAKE_CURRENT_LIST_DIR}/h5run_rows.c
            ${CMAKE_CURRENT_LIST_DIR}/h5run_stop.c
            ${CMAKE_CURRENT_LIST_DIR}/h5util.c ${PROJECT_SOURCE_DIR}/src/util/fail.c)
set_target_properties(catchup_h5_objects PROPERTIES C_VISIBILITY_PRESET hidden)
target_include_directories(catchup_h5_objects PRIVATE
  ${PROJECT_SOURCE_DIR}/include ${PROJECT_BINARY_DIR}/include ${PROJECT_SOURCE_DIR}/src)
target_link_libraries(catchup_h5_objects PRIVATE hdf5::hdf5_hl hdf5::hdf5 MPI::MPI_C catchup_warnings)
add_library(catchup_h5_static STATIC $<TARGET_OBJECTS:catchup_h5_objects>)
# Its users include the internal h5util.h, which includes hdf5.h: HDF5 and
# MPI (whose headers the parallel HDF5 headers include) are PUBLIC here.
target_link_libraries(catchup_h5_static PUBLIC catchup_static hdf5::hdf5_hl hdf5::hdf5 MPI::MPI_C)
add_library(catchup_h5 SHARED $<TARGET_OBJECTS:catchup_h5_objects>)
set_target_properties(catchup_h5 PROPERTIES
  VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}
  EXPORT_NAME catchup_h5
  INSTALL_RPATH "$ORIGIN")   # finds libcatchup beside it, wherever installed
target_link_libraries(catchup_h5 PUBLIC catchup
                      PRIVATE hdf5::hdf5_hl hdf5::hdf5 MPI::MPI_C catchup_warnings)
add_library(catchup::catchup_h5 ALIAS catchup_h5)

install(TARGETS catchup_h5 EXPORT catchupTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
