! catchup_c -- raw bind(C) interfaces to every function of libcatchup
! declared in include/catchup/{status,version,polyset,projector,input,lcs,
! integrator}.h, named c_<C name>. The friendly wrappers of module `catchup`
! are built on these; they are public for callers who want the C calling
! convention itself (handles are the `ptr` member of the cup_*_t types).
!
! Conventions: `T **out` is `type(c_ptr)` by reference; `T *` of a handle is
! `type(c_ptr), value`; a pointer that may be NULL is `type(c_ptr), value`;
! a non-NULL array is an assumed-size dummy (no copy for a contiguous actual);
! `long` is c_long, `unsigned long` sizes are passed as c_long (same width).
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

    ! ---- status.h, version.h --------------------------------------------------
    function c_cup_status_string(status) bind(C, name="cup_status_string") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: status
      type(c_ptr) :: s
    end function c_cup_status_string
    function c_cup_status_name(status) bind(C, name="cup_status_name") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: status
      type(c_ptr) :: s
    end function c_cup_status_name
    function c_cup_version() bind(C, name="cup_version") result(s)
      import :: c_ptr
      type(c_ptr) :: s
    end function c_cup_version
    function c_cup_dependency_versions(buf, size) bind(C, name="cup_dependency_versions") result(n)
      import :: c_int, c_long, c_char
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_long), value :: size
      integer(c_int) :: n
    end function c_cup_dependency_versions

    ! ---- polyset.h ------------------------------------------------------------
    function c_cup_polyset_create(K, C, g, P, errmsg) bind(C, name="cup_polyset_create") result(st)
      import :: c_int, c_ptr, c_char, cup_csc
      type(c_ptr), intent(out) :: K
      type(cup_csc), intent(in) :: C
      type(c_ptr), value :: g, P
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_polyset_create
    subroutine c_cup_polyset_free(K) bind(C, name="cup_polyset_free")
      import :: c_ptr
      type(c_ptr), intent(inout) :: K
    end subroutine c_cup_polyset_free
    function c_cup_polyset_dim(K) bind(C, name="cup_polyset_dim") result(n)
      import :: c_int, c_ptr
      type(c_ptr), value :: K
      integer(c_int) :: n
    end function c_cup_polyset_dim
    function c_cup_polyset_rows(K) bind(C, name="cup_polyset_rows") result(n)
      import :: c_int, c_ptr
      type(c_ptr), value :: K
      integer(c_int) :: n
    end function c_cup_polyset_rows
    function c_cup_polyset_lipschitz(K) bind(C, name="cup_polyset_lipschitz") result(L)
      import :: c_double, c_ptr
      type(c_ptr), value :: K
      real(c_double) :: L
    end function c_cup_polyset_lipschitz
    function c_cup_polyset_norm(K, v) bind(C, name="cup_polyset_norm") result(nrm)
      import :: c_double, c_ptr
      type(c_ptr), value :: K
      real(c_double), intent(in) :: v(*)
      real(c_double) :: nrm
    end function c_cup_polyset_norm
    function c_cup_polyset_contains(K, g, x) bind(C, name="cup_polyset_contains") result(yes)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: K, g
      real(c_double), intent(in) :: x(*)
      integer(c_int) :: yes
    end function c_cup_polyset_contains
    function c_cup_polyset_interior_direction(K) bind(C, name="cup_polyset_interior_direction") result(d)
      import :: c_ptr
      type(c_ptr), value :: K
      type(c_ptr) :: d
    end function c_cup_polyset_interior_direction

    ! ---- projector.h ----------------------------------------------------------
    subroutine c_cup_projector_options_default(opt) bind(C, name="cup_projector_options_default")
      import :: cup_projector_options
      type(cup_projector_options), intent(inout) :: opt
    end subroutine c_cup_projector_options_default
    function c_cup_projector_create(p, K, opt, errmsg) bind(C, name="cup_projector_create") result(st)
      import :: c_int, c_ptr, c_char, cup_projector_options
      type(c_ptr), intent(out) :: p
      type(c_ptr), value :: K
      type(cup_projector_options), intent(in) :: opt
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_projector_create
    subroutine c_cup_projector_free(p) bind(C, name="cup_projector_free")
      import :: c_ptr
      type(c_ptr), intent(inout) :: p
    end subroutine c_cup_projector_free
    function c_cup_projector_set_offset(p, g) bind(C, name="cup_projector_set_offset") result(st)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: p
      real(c_double), intent(in) :: g(*)
      integer(c_int) :: st
    end function c_cup_projector_set_offset
    function c_cup_projector_set_tolerances(p, eps_abs, eps_rel, eta_abs, eta_rel) &
        bind(C, name="cup_projector_set_tolerances") result(st)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: p
      real(c_double), value :: eps_abs, eps_rel, eta_abs, eta_rel
      integer(c_int) :: st
    end function c_cup_projector_set_tolerances
    ! No wrapper in module catchup yet (owed: tests/fortran/check_coverage.sh).
    function c_cup_projector_offer_feasible(p, w) bind(C, name="cup_projector_offer_feasible") result(yes)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: p
      real(c_double), intent(in) :: w(*)
      integer(c_int) :: yes
    end function c_cup_projector_offer_feasible
    subroutine c_cup_projector_reset(p) bind(C, name="cup_projector_reset")
      import :: c_ptr
      type(c_ptr), value :: p
    end subroutine c_cup_projector_reset
    function c_cup_project(p, x, z, info) bind(C, name="cup_project") result(st)
      import :: c_int, c_double, c_ptr, cup_proj_info
      type(c_ptr), value :: p
      real(c_double), intent(in) :: x(*)
      real(c_double), intent(inout) :: z(*)
      type(cup_proj_info), intent(inout) :: info
      integer(c_int) :: st
    end function c_cup_project
    function c_cup_projector_lambda(p) bind(C, name="cup_projector_lambda") result(v)
      import :: c_ptr
      type(c_ptr), value :: p
      type(c_ptr) :: v
    end function c_cup_projector_lambda
    function c_cup_projector_feasible(p) bind(C, name="cup_projector_feasible") result(v)
      import :: c_ptr
      type(c_ptr), value :: p
      type(c_ptr) :: v
    end function c_cup_projector_feasible
    function c_cup_projector_farkas(p) bind(C, name="cup_projector_farkas") result(v)
      import :: c_ptr
      type(c_ptr), value :: p
      type(c_ptr) :: v
    end function c_cup_projector_farkas
    function c_cup_proj_method_name(method) bind(C, name="cup_proj_method_name") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: method
      type(c_ptr) :: s
    end function c_cup_proj_method_name
    function c_cup_proj_method_parse(name) bind(C, name="cup_proj_method_parse") result(method)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: name(*)
      integer(c_int) :: method
    end function c_cup_proj_method_parse

    ! ---- input.h --------------------------------------------------------------
    function c_cup_input_create(u, p, errmsg) bind(C, name="cup_input_create") result(st)
      import :: c_int, c_ptr, c_char
      type(c_ptr), intent(out) :: u
      integer(c_int), value :: p
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_input_create
    subroutine c_cup_input_free(u) bind(C, name="cup_input_free")
      import :: c_ptr
      type(c_ptr), intent(inout) :: u
    end subroutine c_cup_input_free
    function c_cup_input_add(u, j, w, errmsg) bind(C, name="cup_input_add") result(st)
      import :: c_int, c_ptr, c_char, cup_wave
      type(c_ptr), value :: u
      integer(c_int), value :: j
      type(cup_wave), intent(in) :: w
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_input_add
    function c_cup_input_set_callback(u, fn, ctx, abs_tol, rel_tol) &
        bind(C, name="cup_input_set_callback") result(st)
      import :: c_int, c_double, c_ptr, c_funptr
      type(c_ptr), value :: u
      type(c_funptr), value :: fn
      type(c_ptr), value :: ctx
      real(c_double), value :: abs_tol, rel_tol
      integer(c_int) :: st
    end function c_cup_input_set_callback
    function c_cup_input_dim(u) bind(C, name="cup_input_dim") result(p)
      import :: c_int, c_ptr
      type(c_ptr), value :: u
      integer(c_int) :: p
    end function c_cup_input_dim
    function c_cup_input_is_constant(u) bind(C, name="cup_input_is_constant") result(yes)
      import :: c_int, c_ptr
      type(c_ptr), value :: u
      integer(c_int) :: yes
    end function c_cup_input_is_constant
    function c_cup_input_eval(u, t, out) bind(C, name="cup_input_eval") result(st)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: u
      real(c_double), value :: t
      real(c_double), intent(inout) :: out(*)
      integer(c_int) :: st
    end function c_cup_input_eval
    function c_cup_input_integral(u, a, b, out) bind(C, name="cup_input_integral") result(st)
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: u
      real(c_double), value :: a, b
      real(c_double), intent(inout) :: out(*)
      integer(c_int) :: st
    end function c_cup_input_integral
    function c_cup_input_next_break(u, t) bind(C, name="cup_input_next_break") result(tb)
      import :: c_double, c_ptr
      type(c_ptr), value :: u
      real(c_double), value :: t
      real(c_double) :: tb
    end function c_cup_input_next_break

    ! ---- lcs.h ----------------------------------------------------------------
    function c_cup_lcs_create(L, d, errmsg) bind(C, name="cup_lcs_create") result(st)
      import :: c_int, c_ptr, c_char, cup_lcs_desc
      type(c_ptr), intent(out) :: L
      type(cup_lcs_desc), intent(in) :: d
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_lcs_create
    subroutine c_cup_lcs_free(L) bind(C, name="cup_lcs_free")
      import :: c_ptr
      type(c_ptr), intent(inout) :: L
    end subroutine c_cup_lcs_free
    function c_cup_lcs_dim(L) bind(C, name="cup_lcs_dim") result(n)
      import :: c_int, c_ptr
      type(c_ptr), value :: L
      integer(c_int) :: n
    end function c_cup_lcs_dim
    function c_cup_lcs_has_D(L) bind(C, name="cup_lcs_has_D") result(f)
      import :: c_ptr, c_int
      type(c_ptr), value :: L
      integer(c_int) :: f
    end function c_cup_lcs_has_D
    function c_cup_lcs_rows(L) bind(C, name="cup_lcs_rows") result(n)
      import :: c_int, c_ptr
      type(c_ptr), value :: L
      integer(c_int) :: n
    end function c_cup_lcs_rows
    function c_cup_lcs_inputs(L) bind(C, name="cup_lcs_inputs") result(n)
      import :: c_int, c_ptr
      type(c_ptr), value :: L
      integer(c_int) :: n
    end function c_cup_lcs_inputs
    function c_cup_lcs_polyset(L) bind(C, name="cup_lcs_polyset") result(K)
      import :: c_ptr
      type(c_ptr), value :: L
      type(c_ptr) :: K
    end function c_cup_lcs_polyset
    function c_cup_lcs_fixed_set(L) bind(C, name="cup_lcs_fixed_set") result(yes)
      import :: c_int, c_ptr
      type(c_ptr), value :: L
      integer(c_int) :: yes
    end function c_cup_lcs_fixed_set
    function c_cup_lcs_circuit(L, c, errmsg) bind(C, name="cup_lcs_circuit") result(st)
      import :: c_int, c_ptr, c_char, cup_circuit
      type(c_ptr), intent(out) :: L
      type(cup_circuit), intent(in) :: c
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_lcs_circuit

    ! ---- integrator.h ---------------------------------------------------------
    function c_cup_schedule_parse(spec, out, errmsg) bind(C, name="cup_schedule_parse") result(st)
      import :: c_int, c_char, cup_schedule
      character(kind=c_char), intent(in) :: spec(*)
      type(cup_schedule), intent(inout) :: out
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_schedule_parse
    function c_cup_schedule_value(s, n) bind(C, name="cup_schedule_value") result(v)
      import :: c_long, c_double, cup_schedule
      type(cup_schedule), intent(in) :: s
      integer(c_long), value :: n
      real(c_double) :: v
    end function c_cup_schedule_value
    function c_cup_schedule_format(s, buf, size) bind(C, name="cup_schedule_format") result(n)
      import :: c_int, c_long, c_char, cup_schedule
      type(cup_schedule), intent(in) :: s
      character(kind=c_char), intent(inout) :: buf(*)
      integer(c_long), value :: size
      integer(c_int) :: n
    end function c_cup_schedule_format
    subroutine c_cup_integrator_options_default(o) bind(C, name="cup_integrator_options_default")
      import :: cup_integrator_options
      type(cup_integrator_options), intent(inout) :: o
    end subroutine c_cup_integrator_options_default
    function c_cup_integrator_create(I, L, u, o, errmsg) bind(C, name="cup_integrator_create") result(st)
      import :: c_int, c_ptr, c_char, cup_integrator_options
      type(c_ptr), intent(out) :: I
      type(c_ptr), value :: L, u
      type(cup_integrator_options), intent(in) :: o
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_integrator_create
    function c_cup_integrator_create_process(I, d, o, errmsg) bind(C, name="cup_integrator_create_process") &
        result(st)
      import :: c_int, c_ptr, c_char, cup_process_desc, cup_integrator_options
      type(c_ptr), intent(out) :: I
      type(cup_process_desc), intent(in) :: d
      type(cup_integrator_options), intent(in) :: o
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_integrator_create_process
    subroutine c_cup_integrator_free(I) bind(C, name="cup_integrator_free")
      import :: c_ptr
      type(c_ptr), intent(inout) :: I
    end subroutine c_cup_integrator_free
    function c_cup_integrator_run(I, x0, sink, sink_ctx, info) bind(C, name="cup_integrator_run") result(st)
      import :: c_int, c_double, c_ptr, c_funptr, cup_run_info
      type(c_ptr), value :: I
      real(c_double), intent(in) :: x0(*)
      type(c_funptr), value :: sink
      type(c_ptr), value :: sink_ctx
      type(cup_run_info), intent(inout) :: info
      integer(c_int) :: st
    end function c_cup_integrator_run
    function c_cup_integrator_checkpoint_size(I) bind(C, name="cup_integrator_checkpoint_size") result(n)
      import :: c_ptr, c_long
      type(c_ptr), value :: I
      integer(c_long) :: n
    end function c_cup_integrator_checkpoint_size
    function c_cup_integrator_checkpoint_save(I, info, buf, size) bind(C, name="cup_integrator_checkpoint_save") &
        result(st)
      import :: c_ptr, c_int, c_long, cup_run_info
      type(c_ptr), value :: I
      type(cup_run_info), intent(in) :: info
      type(c_ptr), value :: buf
      integer(c_long), value :: size
      integer(c_int) :: st
    end function c_cup_integrator_checkpoint_save
    function c_cup_integrator_checkpoint_restore(I, buf, size, errmsg) &
        bind(C, name="cup_integrator_checkpoint_restore") result(st)
      import :: c_ptr, c_int, c_long, c_char
      type(c_ptr), value :: I
      type(c_ptr), value :: buf
      integer(c_long), value :: size
      character(kind=c_char), intent(inout) :: errmsg(*)
      integer(c_int) :: st
    end function c_cup_integrator_checkpoint_restore
    function c_cup_integrator_resume(I, sink, sink_ctx, info) bind(C, name="cup_integrator_resume") result(st)
      import :: c_int, c_ptr, c_funptr, cup_run_info
      type(c_ptr), value :: I
      type(c_funptr), value :: sink
      type(c_ptr), value :: sink_ctx
      type(cup_run_info), intent(inout) :: info
      integer(c_int) :: st
    end function c_cup_integrator_resume
    function c_cup_integrator_zeta(I, zeta) bind(C, name="cup_integrator_zeta") result(st)
      import :: c_ptr, c_int, c_double
      type(c_ptr), value :: I
      real(c_double), intent(out) :: zeta(*)
      integer(c_int) :: st
    end function c_cup_integrator_zeta
    function c_cup_integrator_rows(I) bind(C, name="cup_integrator_rows") result(m)
      import :: c_ptr, c_int
      type(c_ptr), value :: I
      integer(c_int) :: m
    end function c_cup_integrator_rows
    function c_cup_integrator_state(I) bind(C, name="cup_integrator_state") result(x)
      import :: c_ptr
      type(c_ptr), value :: I
      type(c_ptr) :: x
    end function c_cup_integrator_state
    function c_cup_scheme_name(scheme) bind(C, name="cup_scheme_name") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: scheme
      type(c_ptr) :: s
    end function c_cup_scheme_name
    function c_cup_scheme_parse(name) bind(C, name="cup_scheme_parse") result(scheme)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: name(*)
      integer(c_int) :: scheme
    end function c_cup_scheme_parse
    function c_cup_output_name(output) bind(C, name="cup_output_name") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: output
      type(c_ptr) :: s
    end function c_cup_output_name
    function c_cup_output_parse(name) bind(C, name="cup_output_parse") result(v)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: name(*)
      integer(c_int) :: v
    end function c_cup_output_parse
    function c_cup_wave_name(kind) bind(C, name="cup_wave_name") result(s)
      import :: c_int, c_ptr
      integer(c_int), value :: kind
      type(c_ptr) :: s
    end function c_cup_wave_name
    function c_cup_wave_parse(name) bind(C, name="cup_wave_parse") result(v)
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: name(*)
      integer(c_int) :: v
    end function c_cup_wave_parse
  end interface
end module catchup_c
