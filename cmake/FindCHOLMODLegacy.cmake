# CHOLMOD from SuiteSparse 5.x, which ships neither CMake config files nor a
# pkg-config file: find the header and libraries by hand and wrap them in an
# imported target `catchup_cholmod`.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY NAMES cholmod)
find_library(SUITESPARSECONFIG_LIBRARY NAMES suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMODLegacy
  REQUIRED_VARS CHOLMOD_LIBRARY SUITESPARSECONFIG_LIBRARY CHOLMOD_INCLUDE_DIR)
if(CHOLMODLegacy_FOUND AND NOT TARGET catchup_cholmod)
  add_library(catchup_cholmod INTERFACE IMPORTED)
  target_include_directories(catchup_cholmod INTERFACE ${CHOLMOD_INCLUDE_DIR})
  target_link_libraries(catchup_cholmod INTERFACE
    ${CHOLMOD_LIBRARY} ${SUITESPARSECONFIG_LIBRARY})
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_LIBRARY SUITESPARSECONFIG_LIBRARY)
