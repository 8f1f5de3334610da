! catchup -- the Fortran 2003 interface of the catchup library: `use catchup`
! gives every constant, type and wrapper of include/catchup.h (the HDF5 run
! writer, include/catchup/h5run.h, is module catchup_h5run). The raw bind(C)
! interfaces are in module catchup_c (and catchup_scene: c_cup_scene_*).
!
! Preprocessed: CATCHUP_HAVE_SCENE is defined when libcatchup contains the
! scene loader (src/io/scene.c), whose wrappers need its symbols to link.
module catchup
  use catchup_constants
  use catchup_types
  use catchup_base, only: cup_c_string, cup_f_c_string, cup_chars_to_string, &
    cup_status_string, cup_status_name, cup_status_merge, cup_version, cup_dependency_versions, &
    cup_csc_from_fortran, cup_csc_from_dense, cup_csc_view, cup_csc_free
  use catchup_core
  use catchup_netlist
  use catchup_pss
#ifdef CATCHUP_HAVE_SCENE
  use catchup_scene, only: cup_scene_load, cup_scene_load_string, cup_scene_free, cup_scene_netlist, &
    cup_scene_name, cup_scene_lcs, cup_scene_input, cup_scene_x0, cup_scene_options, &
    cup_scene_eps_spec, cup_scene_eta_spec, cup_scene_text, cup_scene_process, cup_scene_dim, &
    cup_scene_integrator, cup_scene_state_name, cup_scene_state_unit, cup_scene_file_count, cup_scene_file, &
    cup_scene_file_sha256, cup_scene_check_output, cup_scene_max_steps
#endif
  implicit none
  public
  !> .true. when the scene wrappers (cup_scene_*) are part of this build
#ifdef CATCHUP_HAVE_SCENE
  logical, parameter :: CUP_HAVE_SCENE = .true.
#else
  logical, parameter :: CUP_HAVE_SCENE = .false.
#endif
end module catchup
