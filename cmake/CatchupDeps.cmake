# Finding every dependency, each with the Debian package that provides it.
# A missing dependency stops configuration with a message that names the
# package to install, instead of a CMake backtrace.

function(catchup_missing what package)
  message(FATAL_ERROR
    "catchup: ${what} was not found.\n"
    "  On Debian/Ubuntu install it with:  apt-get install ${package}\n"
    "  (or run scripts/setup, which installs every missing package).")
endfunction()

find_package(PkgConfig QUIET)

# catchup_pkg(TARGET PREFIX MODULE): TARGET, an interface over pkg-config's
# MODULE (PkgConfig::PREFIX), when pkg-config knows it; PREFIX_FOUND says
# whether it did.
macro(catchup_pkg target prefix module)
  set(${prefix}_FOUND FALSE)
  if(PKG_CONFIG_FOUND)
    pkg_check_modules(${prefix} QUIET IMPORTED_TARGET ${module})
    if(${prefix}_FOUND)
      add_library(${target} INTERFACE IMPORTED)
      target_link_libraries(${target} INTERFACE PkgConfig::${prefix})
    endif()
  endif()
endmacro()

# --- GSL (quadrature, special functions) ---------------------------------
find_package(GSL QUIET)
if(NOT GSL_FOUND)
  catchup_missing("GSL (GNU Scientific Library)" "libgsl-dev")
endif()

# catchup_gsl_static: GSL's static archive and the system BLAS for its CBLAS
# calls, for the programs (apps/CMakeLists.txt says why). libgsl.so resolves
# those calls to libblas.so.3, which CHOLMOD's LAPACK loads first, so the
# programs' results are the same bits either way. Without libgsl.a or
# libblas.so (or with -DCATCHUP_STATIC_GSL=OFF) the programs link libgsl.so.
option(CATCHUP_STATIC_GSL "Link GSL statically into catchup-run and catchup-sweep" ON)
if(CATCHUP_STATIC_GSL)
  find_library(CATCHUP_GSL_ARCHIVE NAMES libgsl.a)
  find_library(CATCHUP_BLAS_LIBRARY NAMES blas)
  if(CATCHUP_GSL_ARCHIVE AND CATCHUP_BLAS_LIBRARY)
    add_library(catchup_gsl_static INTERFACE)
    target_link_libraries(catchup_gsl_static INTERFACE ${CATCHUP_GSL_ARCHIVE} ${CATCHUP_BLAS_LIBRARY})
  else()
    message(STATUS "catchup: libgsl.a or libblas.so not found; the programs link libgsl.so")
  endif()
endif()

# --- CHOLMOD (SuiteSparse): prefer SuiteSparse 7+ config files ---------------
find_package(CHOLMOD CONFIG QUIET)
if(TARGET SuiteSparse::CHOLMOD)
  add_library(catchup_cholmod INTERFACE IMPORTED)
  target_link_libraries(catchup_cholmod INTERFACE SuiteSparse::CHOLMOD)
else()
  find_package(CHOLMODLegacy MODULE QUIET)
  if(NOT CHOLMODLegacy_FOUND)
    catchup_missing("CHOLMOD (SuiteSparse)" "libsuitesparse-dev")
  endif()
endif()

# --- libyaml (scene and sweep files) ---------------------------------------
catchup_pkg(catchup_yaml YAML yaml-0.1)
if(NOT YAML_FOUND)
  find_path(YAML_INCLUDE_DIR yaml.h)
  find_library(YAML_LIBRARY NAMES yaml)
  if(NOT YAML_INCLUDE_DIR OR NOT YAML_LIBRARY)
    catchup_missing("libyaml" "libyaml-dev")
  endif()
  add_library(catchup_yaml INTERFACE IMPORTED)
  target_include_directories(catchup_yaml INTERFACE ${YAML_INCLUDE_DIR})
  target_link_libraries(catchup_yaml INTERFACE ${YAML_LIBRARY})
endif()

# --- MPI and HDF5: only for src/io's HDF5 part and the apps -----------------
if(CATCHUP_BUILD_APPS)
  set(_mpi_langs C)
  if(CATCHUP_BUILD_FORTRAN)
    list(APPEND _mpi_langs Fortran)
  endif()
  find_package(MPI QUIET COMPONENTS ${_mpi_langs})
  if(NOT MPI_C_FOUND)
    catchup_missing("MPI for C (Open MPI)" "libopenmpi-dev openmpi-bin")
  endif()
  if(CATCHUP_BUILD_FORTRAN AND NOT MPI_Fortran_FOUND)
    catchup_missing("MPI for Fortran (Open MPI)" "libopenmpi-dev gfortran")
  endif()
  # Parallel and serial HDF5 sit side by side on Debian; a plain find may pick
  # the serial one. We need the build that matches our MPI.
  set(HDF5_PREFER_PARALLEL TRUE)
  # HL: the dimension scales (H5DS) that tie /x to /t for netCDF readers.
  find_package(HDF5 QUIET COMPONENTS C HL)
  if(NOT HDF5_FOUND OR NOT HDF5_HL_FOUND)
    catchup_missing("HDF5 with its high-level library (parallel build)" "libhdf5-openmpi-dev hdf5-tools")
  endif()
  if(NOT TARGET hdf5::hdf5)
    add_library(hdf5::hdf5 INTERFACE IMPORTED)
    target_include_directories(hdf5::hdf5 INTERFACE ${HDF5_C_INCLUDE_DIRS} ${HDF5_INCLUDE_DIRS})
    target_link_libraries(hdf5::hdf5 INTERFACE ${HDF5_C_LIBRARIES} ${HDF5_LIBRARIES})
    target_compile_definitions(hdf5::hdf5 INTERFACE ${HDF5_C_DEFINITIONS} ${HDF5_DEFINITIONS})
  endif()
  if(NOT TARGET hdf5::hdf5_hl)
    add_library(hdf5::hdf5_hl INTERFACE IMPORTED)
    target_link_libraries(hdf5::hdf5_hl INTERFACE ${HDF5_C_HL_LIBRARIES} ${HDF5_HL_LIBRARIES} hdf5::hdf5)
  endif()
endif()

# --- cmocka: tests only -------------------------------------------------------
if(CATCHUP_BUILD_TESTS)
  catchup_pkg(catchup_cmocka CMOCKA cmocka)
  if(NOT CMOCKA_FOUND)
    catchup_missing("cmocka (unit test framework)" "libcmocka-dev")
  endif()
endif()
