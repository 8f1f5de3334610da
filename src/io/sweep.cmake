# catchup_sweep: the sweep file, its tasks and the results file of
# catchup-sweep (src/io/sweep*.c). Internal (static, not installed): its
# header src/io/sweep.h is not part of the public API. Included from
# src/CMakeLists.txt with the apps, since the results file needs HDF5. It uses
# the scene loader's YAML tree (scene_tree.c) and read_text.c, internal to
# the library: hence catchup_static (and catchup_h5_static for its users).
add_library(catchup_sweep STATIC
  ${CMAKE_CURRENT_LIST_DIR}/sweep.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_run.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_h5.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_h5_create.c
  ${CMAKE_CURRENT_LIST_DIR}/sweep_crowd.c)
target_include_directories(catchup_sweep PUBLIC ${CMAKE_CURRENT_LIST_DIR} PRIVATE ${PROJECT_SOURCE_DIR}/src)
target_link_libraries(catchup_sweep PUBLIC catchup_static hdf5::hdf5_hl hdf5::hdf5 MPI::MPI_C
                      PRIVATE catchup_warnings m)
