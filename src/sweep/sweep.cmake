# catchup_sweep: the sweep file, its tasks and the results file of
# catchup-sweep (src/sweep/). Internal (static, not installed): its headers
# are not part of the public API. Included from src/CMakeLists.txt with the
# apps, since the results file needs HDF5. It uses the scene loader's YAML
# tree (io/scene_tree.c), io/read_text.c and the HDF5 writers' helpers
# (h5/h5util.c), internal to the libraries: hence catchup_h5_static (over
# catchup_static). Its users include its headers, which include "io/...":
# both folders are PUBLIC include directories.
add_library(catchup_sweep STATIC
  ${CMAKE_CURRENT_LIST_DIR}/sweep_gen.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_variant.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_run.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_h5.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_crowd.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_steady.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_file.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_file_create.c)
target_include_directories(catchup_sweep PUBLIC ${CMAKE_CURRENT_LIST_DIR} ${PROJECT_SOURCE_DIR}/src)
target_link_libraries(catchup_sweep PUBLIC catchup_h5_static hdf5::hdf5_hl hdf5::hdf5 MPI::MPI_C
                      PRIVATE catchup_warnings m)
