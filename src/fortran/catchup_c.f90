! catchup_c -- raw bind(C) interfaces to every function of libcatchup
! declared in include/catchup/{status,version,polyset,projector,input,lcs,
! integrator}.h, named c_<C name>, generated from those headers at build time
! (gen_bindings.py writes bind_<header>.inc; the public list below is this
! module's choice). The friendly wrappers of module `catchup` are built on
! these; they are public for callers who want the C calling convention itself
! (handles are the `ptr` member of the cup_*_t types).
!
! Conventions (gen_bindings.py's rules): `T **out` is `type(c_ptr)` by
! reference; `T *` of a handle is `type(c_ptr), value`; a pointer that may be
! NULL is `type(c_ptr), value`; a non-NULL array is an assumed-size dummy (no
! copy for a contiguous actual); `long` is c_long, `unsigned long` sizes are
! passed as c_long (same width).
module catchup_c
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_size_t, c_double, c_char, &
    c_ptr, c_funptr
  use catchup_types
  implicit none
  private
  public :: c_strlen
  public :: c_cup_status_string, c_cup_status_name
  public :: c_cup_version, c_cup_dependency_versions
  public :: c_cup_polyset_create, c_cup_polyset_free, c_cup_polyset_dim, c_cup_polyset_rows, &
    c_cup_polyset_lipschitz, c_cup_polyset_norm, c_cup_polyset_contains, &
    c_cup_polyset_interior_direction
  public :: c_cup_projector_options_default, c_cup_projector_create, c_cup_projector_free, &
    c_cup_projector_set_offset, c_cup_projector_set_tolerances, c_cup_projector_offer_feasible, &
    c_cup_projector_reset, c_cup_project, c_cup_projector_lambda, c_cup_projector_feasible, &
    c_cup_projector_farkas, c_cup_proj_method_name, c_cup_proj_method_parse
  public :: c_cup_input_create, c_cup_input_free, c_cup_input_add, c_cup_input_set_callback, &
    c_cup_input_dim, c_cup_input_is_constant, c_cup_input_eval, c_cup_input_integral, &
    c_cup_input_next_break
  public :: c_cup_lcs_create, c_cup_lcs_free, c_cup_lcs_dim, c_cup_lcs_rows, c_cup_lcs_inputs, c_cup_lcs_has_D, &
    c_cup_lcs_polyset, c_cup_lcs_fixed_set, c_cup_lcs_circuit
  public :: c_cup_schedule_parse, c_cup_schedule_value, c_cup_schedule_format, &
    c_cup_integrator_options_default, c_cup_integrator_create, c_cup_integrator_create_process, &
    c_cup_integrator_free, &
    c_cup_integrator_run, c_cup_integrator_state, c_cup_integrator_zeta, c_cup_integrator_rows, &
    c_cup_integrator_checkpoint_size, &
    c_cup_integrator_checkpoint_save, c_cup_integrator_checkpoint_restore, c_cup_integrator_resume, &
    c_cup_scheme_name, c_cup_scheme_parse, &
    c_cup_output_name, c_cup_output_parse, c_cup_wave_name, c_cup_wave_parse

  interface
    ! ---- libc -----------------------------------------------------------------
    function c_strlen(s) bind(C, name="strlen") result(n)
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
      integer(c_size_t) :: n
    end function c_strlen
  end interface

  ! The raw bind(C) interfaces c_<C name>, generated from the headers at build time (gen_bindings.py)
  include "bind_status.inc"
  include "bind_version.inc"
  include "bind_polyset.inc"
  include "bind_projector.inc"
  include "bind_input.inc"
  include "bind_lcs.inc"
  include "bind_integrator.inc"
end module catchup_c
