! catchup_core -- Fortran wrappers of polyset.h, projector.h, input.h, lcs.h
! and integrator.h (conventions in catchup_base). Component indices of an
! input (cup_input_add_*: j) are 1-based here, as Fortran users count; every
! other number is the C one (steps k = 0..n, status codes, enum values).
module catchup_core
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_funptr, &
    c_null_ptr, c_null_funptr, c_associated, c_f_pointer, c_loc, c_funloc
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use catchup_constants
  use catchup_types
  use catchup_c
  use catchup_base
  implicit none
  private

  public :: cup_polyset_create, cup_polyset_free, cup_polyset_dim, cup_polyset_rows, &
    cup_polyset_lipschitz, cup_polyset_norm, cup_polyset_contains, cup_polyset_interior_direction
  public :: cup_projector_options_default, cup_projector_create, cup_projector_free, &
    cup_projector_set_offset, cup_projector_set_tolerances, &
    cup_projector_reset, cup_project, cup_projector_lambda, cup_projector_feasible, &
    cup_projector_farkas, cup_proj_method_name, cup_proj_method_parse
  public :: cup_input_create, cup_input_free, cup_input_add, cup_input_add_constant, &
    cup_input_add_sine, cup_input_add_square, cup_input_add_pwl, cup_input_set_callback, &
    cup_input_dim, cup_input_is_constant, cup_input_eval, cup_input_integral, cup_input_next_break
  public :: cup_lcs_create, cup_lcs_create_dense, cup_lcs_circuit, cup_lcs_free, cup_lcs_dim, &
    cup_lcs_rows, cup_lcs_inputs, cup_lcs_polyset, cup_lcs_fixed_set
  public :: cup_schedule_parse, cup_schedule_value, cup_schedule_format, &
    cup_integrator_options_default, cup_integrator_create, cup_integrator_free, &
    cup_integrator_run, cup_integrator_run_store, cup_integrator_state, &
    cup_scheme_name, cup_scheme_parse, cup_output_name, cup_output_parse, cup_wave_name, &
    cup_wave_parse, cup_run_info_message

  !> value(n) = coef * n^power, for a default-kind or a c_long n
  interface cup_schedule_value
    module procedure schedule_value_int, schedule_value_long
  end interface cup_schedule_value

  !> What cup_integrator_run_store's sink fills (grown by doubling).
  type :: store_t
    integer :: dim = 0
    integer :: count = 0
    integer(c_long) :: last_k = -1
    logical :: nomem = .false.
    real(c_double), allocatable :: t(:)
    real(c_double), allocatable :: X(:, :)
  end type store_t

contains

  ! ---- small helpers -----------------------------------------------------------

  !> ierr = CUP_ERR_DIM with "<what> has <got> entries, expected <want>".
  subroutine size_fail(what, got, want, ierr, errmsg)
    character(len=*), intent(in) :: what
    integer, intent(in) :: got, want
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(len=200) :: msg
    write(msg, '(a,a,i0,a,i0)') what, ' has ', got, ' entries, expected ', want
    call cup_fail_(CUP_ERR_DIM, trim(msg), ierr, errmsg)
  end subroutine size_fail

  logical function null_fail(p, what, ierr, errmsg)
    type(c_ptr), intent(in) :: p
    character(len=*), intent(in) :: what
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    null_fail = .not. c_associated(p)
    if (null_fail) then
      call cup_fail_(CUP_ERR_ARG, what // ' handle is null', ierr, errmsg)
    else
      ierr = CUP_OK
    end if
  end function null_fail

  !> Copy n doubles from a C pointer (null: found = .false.).
  subroutine copy_out(p, n, out, found, ierr)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: n
    real(c_double), intent(inout) :: out(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    real(c_double), pointer :: v(:)
    found = c_associated(p)
    ierr = CUP_OK
    if (size(out) < n) then
      ierr = CUP_ERR_DIM
      return
    end if
    if (.not. found) return
    call c_f_pointer(p, v, [n])
    out(1:n) = v
  end subroutine copy_out

  ! Optional array arguments are copied into local allocatables before their
  ! address goes to C (creation-time data, copied by C anyway): gfortran 12
  ! at -O2 crashes when an absent optional assumed-shape actual is forwarded
  ! to an OPTIONAL, CONTIGUOUS dummy, and users do forward optionals.

  ! ---- polyset.h -----------------------------------------------------------------

  !> K = {x : C x + g >= 0} with metric P: identity (default), diag(Pdiag), or
  !> the sparse SPD Psparse (lower triangle only if lower_only). g defaults to 0.
  subroutine cup_polyset_create(K, C, ierr, g, Pdiag, Psparse, lower_only, errmsg)
    type(cup_polyset_t), intent(out) :: K
    type(cup_csc_matrix), intent(in), target :: C
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: g(:), Pdiag(:)
    type(cup_csc_matrix), intent(in), optional, target :: Psparse
    logical, intent(in), optional :: lower_only
    character(len=*), intent(out), optional :: errmsg
    type(cup_metric), target :: P
    real(c_double), allocatable, target :: gl(:), dl(:)   ! see contiguous_copy
    type(c_ptr) :: gp
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (.not. allocated(C%colptr)) then
      call cup_fail_(CUP_ERR_ARG, 'polyset: C is empty (build it with cup_csc_from_*)', ierr, errmsg)
      return
    end if
    gp = c_null_ptr
    if (present(g)) then
      if (size(g) /= C%nrow) then
        call size_fail('polyset: g', size(g), int(C%nrow), ierr, errmsg)
        return
      end if
      gl = g
      if (size(gl) > 0) gp = c_loc(gl)
    end if
    if (present(Pdiag) .and. present(Psparse)) then
      call cup_fail_(CUP_ERR_ARG, 'polyset: give Pdiag or Psparse, not both', ierr, errmsg)
      return
    end if
    if (present(Pdiag)) then
      if (size(Pdiag) /= C%ncol) then
        call size_fail('polyset: Pdiag', size(Pdiag), int(C%ncol), ierr, errmsg)
        return
      end if
      dl = Pdiag
      P%kind = CUP_METRIC_DIAGONAL
      if (size(dl) > 0) P%diag = c_loc(dl)
    else if (present(Psparse)) then
      P%kind = CUP_METRIC_SPARSE
      P%matrix = cup_csc_view(Psparse)
      if (present(lower_only)) P%lower_only = merge(1_c_int, 0_c_int, lower_only)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_polyset_create(K%ptr, cup_csc_view(C), gp, c_loc(P), cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_polyset_create

  !> Free K (a borrowed handle is only forgotten) and null the handle.
  subroutine cup_polyset_free(K)
    type(cup_polyset_t), intent(inout) :: K
    if (.not. K%borrowed) call c_cup_polyset_free(K%ptr)
    K%ptr = c_null_ptr
    K%borrowed = .false.
  end subroutine cup_polyset_free

  integer function cup_polyset_dim(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_dim = int(c_cup_polyset_dim(K%ptr))
  end function cup_polyset_dim

  integer function cup_polyset_rows(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_rows = int(c_cup_polyset_rows(K%ptr))
  end function cup_polyset_rows

  !> Guaranteed upper bound on lambda_max(C P^-1 C^T).
  real(c_double) function cup_polyset_lipschitz(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_lipschitz = c_cup_polyset_lipschitz(K%ptr)
  end function cup_polyset_lipschitz

  !> The P-norm of v (dim entries); NaN if v has the wrong size or K is null.
  real(c_double) function cup_polyset_norm(K, v)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(in) :: v(:)
    if (.not. c_associated(K%ptr)) then
      cup_polyset_norm = ieee_value(0.0_c_double, ieee_quiet_nan)
    else if (size(v) /= c_cup_polyset_dim(K%ptr)) then
      cup_polyset_norm = ieee_value(0.0_c_double, ieee_quiet_nan)
    else
      cup_polyset_norm = c_cup_polyset_norm(K%ptr, v)
    end if
  end function cup_polyset_norm

  !> .true. if x is certainly in {C x + g >= 0} (g: the default offset if
  !> absent); .false. otherwise, also for wrong sizes or a null K.
  logical function cup_polyset_contains(K, x, g)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(in), optional :: g(:)
    real(c_double), allocatable, target :: gl(:)
    type(c_ptr) :: gp
    cup_polyset_contains = .false.
    if (.not. c_associated(K%ptr)) return
    if (size(x) /= c_cup_polyset_dim(K%ptr)) return
    gp = c_null_ptr
    if (present(g)) then
      if (size(g) /= c_cup_polyset_rows(K%ptr)) return
      gl = g
      if (size(gl) > 0) gp = c_loc(gl)
    end if
    cup_polyset_contains = c_cup_polyset_contains(K%ptr, gp, x) /= 0
  end function cup_polyset_contains

  !> A direction d with C d > 0 found at creation (found = .false. if none).
  subroutine cup_polyset_interior_direction(K, d, found, ierr)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(inout) :: d(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (null_fail(K%ptr, 'polyset', ierr)) return
    call copy_out(c_cup_polyset_interior_direction(K%ptr), int(c_cup_polyset_dim(K%ptr)), d, found, ierr)
  end subroutine cup_polyset_interior_direction

  ! ---- projector.h -----------------------------------------------------------------

  !> The library's defaults (from the C function).
  subroutine cup_projector_options_default(opt)
    type(cup_projector_options), intent(out) :: opt
    call c_cup_projector_options_default(opt)
  end subroutine cup_projector_options_default

  !> A projector onto K (K must outlive it). opt defaults to the library's;
  !> feasible_point (dim entries, copied) overrides opt%feasible_point.
  subroutine cup_projector_create(p, K, ierr, opt, feasible_point, errmsg)
    type(cup_projector_t), intent(out) :: p
    type(cup_polyset_t), intent(in) :: K
    integer, intent(out) :: ierr
    type(cup_projector_options), intent(in), optional :: opt
    real(c_double), intent(in), optional :: feasible_point(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_projector_options) :: o
    real(c_double), allocatable, target :: fl(:)
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (null_fail(K%ptr, 'projector: polyset', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call c_cup_projector_options_default(o)
    end if
    if (present(feasible_point)) then
      if (size(feasible_point) /= c_cup_polyset_dim(K%ptr)) then
        call size_fail('projector: feasible_point', size(feasible_point), &
          int(c_cup_polyset_dim(K%ptr)), ierr, errmsg)
        return
      end if
      fl = feasible_point
      if (size(fl) > 0) o%feasible_point = c_loc(fl)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_projector_create(p%ptr, K%ptr, o, cmsg)
    if (st == CUP_OK) then
      p%dim = int(c_cup_polyset_dim(K%ptr))
      p%m = int(c_cup_polyset_rows(K%ptr))
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_projector_create

  subroutine cup_projector_free(p)
    type(cup_projector_t), intent(inout) :: p
    call c_cup_projector_free(p%ptr)
    p%ptr = c_null_ptr
    p%dim = 0
    p%m = 0
  end subroutine cup_projector_free

  !> Replace the offset g (m entries) for the following projections.
  subroutine cup_projector_set_offset(p, g, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: g(:)
    integer, intent(out) :: ierr
    if (null_fail(p%ptr, 'projector', ierr)) return
    if (size(g) /= p%m) then
      call size_fail('g', size(g), p%m, ierr)
      return
    end if
    ierr = int(c_cup_projector_set_offset(p%ptr, g))
  end subroutine cup_projector_set_offset

  subroutine cup_projector_set_tolerances(p, eps_abs, eps_rel, eta_abs, eta_rel, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: eps_abs, eps_rel, eta_abs, eta_rel
    integer, intent(out) :: ierr
    if (null_fail(p%ptr, 'projector', ierr)) return
    ierr = int(c_cup_projector_set_tolerances(p%ptr, eps_abs, eps_rel, eta_abs, eta_rel))
  end subroutine cup_projector_set_tolerances

  !> Forget the warm start.
  subroutine cup_projector_reset(p)
    type(cup_projector_t), intent(in) :: p
    if (c_associated(p%ptr)) call c_cup_projector_reset(p%ptr)
  end subroutine cup_projector_reset

  !> z = an (eps, eta)-approximate P-projection of x (dim entries each; z and
  !> x must be different arrays). ierr: CUP_OK, CUP_WARN_NOT_CERTIFIED,
  !> CUP_ERR_EMPTY_SET (see cup_projector_farkas), CUP_ERR_NONFINITE, ...
  subroutine cup_project(p, x, z, ierr, info)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(inout) :: z(:)
    integer, intent(out) :: ierr
    type(cup_proj_info), intent(out), optional :: info
    type(cup_proj_info) :: pi
    if (null_fail(p%ptr, 'projector', ierr)) return
    if (size(x) /= p%dim) then
      call size_fail('x', size(x), p%dim, ierr)
      return
    end if
    if (size(z) /= p%dim) then
      call size_fail('z', size(z), p%dim, ierr)
      return
    end if
    ierr = int(c_cup_project(p%ptr, x, z, pi))
    if (present(info)) info = pi
  end subroutine cup_project

  !> Multipliers lambda (m entries) of the last projection.
  subroutine cup_projector_lambda(p, lambda, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: lambda(:)
    integer, intent(out) :: ierr
    logical :: found
    if (null_fail(p%ptr, 'projector', ierr)) return
    call copy_out(c_cup_projector_lambda(p%ptr), p%m, lambda, found, ierr)
  end subroutine cup_projector_lambda

  !> The exactly feasible point v (dim entries) of the last projection, if any.
  subroutine cup_projector_feasible(p, v, found, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: v(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (null_fail(p%ptr, 'projector', ierr)) return
    call copy_out(c_cup_projector_feasible(p%ptr), p%dim, v, found, ierr)
  end subroutine cup_projector_feasible

  !> After CUP_ERR_EMPTY_SET: the Farkas certificate y >= 0 (m entries).
  subroutine cup_projector_farkas(p, y, found, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: y(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (null_fail(p%ptr, 'projector', ierr)) return
    call copy_out(c_cup_projector_farkas(p%ptr), p%m, y, found, ierr)
  end subroutine cup_projector_farkas

  function cup_proj_method_name(method) result(s)
    integer, intent(in) :: method
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_proj_method_name(int(method, c_int)))
  end function cup_proj_method_name

  !> "auto", "pg", "fista", "activeset" -> CUP_PROJ_*; -1 if unknown.
  integer function cup_proj_method_parse(name)
    character(len=*), intent(in) :: name
    cup_proj_method_parse = int(c_cup_proj_method_parse(cup_f_c_string(name)))
  end function cup_proj_method_parse

  ! ---- input.h ---------------------------------------------------------------------

  !> An input with p components, zero until terms are added.
  subroutine cup_input_create(u, p, ierr, errmsg)
    type(cup_input_t), intent(out) :: u
    integer, intent(in) :: p
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_input_create(u%ptr, int(p, c_int), cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_create

  subroutine cup_input_free(u)
    type(cup_input_t), intent(inout) :: u
    if (.not. u%borrowed) call c_cup_input_free(u%ptr)
    u%ptr = c_null_ptr
    u%borrowed = .false.
  end subroutine cup_input_free

  !> Add the waveform term w to component j (1-based). For a PWL term, w%t
  !> and w%v are c_loc of w%npoints times/values (copied).
  subroutine cup_input_add(u, j, w, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    type(cup_wave), intent(in) :: w
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (null_fail(u%ptr, 'input', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_input_add(u%ptr, int(j - 1, c_int), w, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_add

  !> u_j(t) += value (j 1-based).
  subroutine cup_input_add_constant(u, j, value, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: value
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    w%kind = CUP_WAVE_CONSTANT
    w%value = value
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_constant

  !> u_j(t) += amplitude sin(2 pi frequency t + phase) (16 sin(6 pi t):
  !> amplitude 16, frequency 3).
  subroutine cup_input_add_sine(u, j, amplitude, frequency, ierr, phase, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: amplitude, frequency
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: phase
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    w%kind = CUP_WAVE_SINE
    w%amplitude = amplitude
    w%frequency = frequency
    if (present(phase)) w%phase = phase
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_sine

  !> u_j(t) += amplitude sign(sin(2 pi frequency t + phase)), sign(0) = 0.
  subroutine cup_input_add_square(u, j, amplitude, frequency, ierr, phase, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: amplitude, frequency
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: phase
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    w%kind = CUP_WAVE_SQUARE
    w%amplitude = amplitude
    w%frequency = frequency
    if (present(phase)) w%phase = phase
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_square

  !> u_j(t) += the piecewise-linear function through (t(i), v(i)) (copied).
  subroutine cup_input_add_pwl(u, j, t, v, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in), target, contiguous :: t(:), v(:)
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    if (size(v) /= size(t)) then
      call size_fail('PWL: v', size(v), size(t), ierr, errmsg)
      return
    end if
    w%kind = CUP_WAVE_PWL
    w%npoints = int(size(t), c_int)
    if (size(t) > 0) then
      w%t = c_loc(t)
      w%v = c_loc(v)
    end if
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_pwl

  !> Replace the waveforms by the callback fn = c_funloc(f) of a bind(C)
  !> procedure(cup_input_fn); ctx (e.g. c_loc of a user derived type) is
  !> passed to it. Integrals by adaptive quadrature to abs_tol / rel_tol.
  subroutine cup_input_set_callback(u, fn, ctx, abs_tol, rel_tol, ierr)
    type(cup_input_t), intent(in) :: u
    type(c_funptr), value :: fn          ! VALUE: a c_funloc(...) actual needs no static temporary
    type(c_ptr), value :: ctx
    real(c_double), intent(in) :: abs_tol, rel_tol
    integer, intent(out) :: ierr
    if (null_fail(u%ptr, 'input', ierr)) return
    ierr = int(c_cup_input_set_callback(u%ptr, fn, ctx, abs_tol, rel_tol))
  end subroutine cup_input_set_callback

  integer function cup_input_dim(u)
    type(cup_input_t), intent(in) :: u
    cup_input_dim = int(c_cup_input_dim(u%ptr))
  end function cup_input_dim

  !> .true. if u does not depend on t.
  logical function cup_input_is_constant(u)
    type(cup_input_t), intent(in) :: u
    cup_input_is_constant = c_cup_input_is_constant(u%ptr) /= 0
  end function cup_input_is_constant

  !> out = u(t) (p entries).
  subroutine cup_input_eval(u, t, out, ierr)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: t
    real(c_double), intent(inout) :: out(:)
    integer, intent(out) :: ierr
    if (null_fail(u%ptr, 'input', ierr)) return
    if (size(out) /= c_cup_input_dim(u%ptr)) then
      call size_fail('out', size(out), int(c_cup_input_dim(u%ptr)), ierr)
      return
    end if
    ierr = int(c_cup_input_eval(u%ptr, t, out))
  end subroutine cup_input_eval

  !> out = the integral of u over [a, b] (p entries).
  subroutine cup_input_integral(u, a, b, out, ierr)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: a, b
    real(c_double), intent(inout) :: out(:)
    integer, intent(out) :: ierr
    if (null_fail(u%ptr, 'input', ierr)) return
    if (size(out) /= c_cup_input_dim(u%ptr)) then
      call size_fail('out', size(out), int(c_cup_input_dim(u%ptr)), ierr)
      return
    end if
    ierr = int(c_cup_input_integral(u%ptr, a, b, out))
  end subroutine cup_input_integral

  !> The next time > t where some term is not smooth (+Inf if none).
  real(c_double) function cup_input_next_break(u, t)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: t
    cup_input_next_break = c_cup_input_next_break(u%ptr, t)
  end function cup_input_next_break

  ! ---- lcs.h -------------------------------------------------------------------------

  !> An LCS from C views (desc%A%... = cup_csc_view(...) of TARGET matrices).
  subroutine cup_lcs_create(L, desc, ierr, errmsg)
    type(cup_lcs_t), intent(out) :: L
    type(cup_lcs_desc), intent(in) :: desc
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_lcs_create(L%ptr, desc, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_lcs_create

  !> An LCS from dense column-major matrices: A (n x n), B (n x m), C (m x n),
  !> E (n x p), F (m), G (m x p), Pdiag (n). n and m come from C; p from E or
  !> G. A zero-size A, B, E, G is absent (B absent: no P B = C^T check), a
  !> zero-size F is 0, a zero-size Pdiag is P = I. The CSC copies are
  !> released once the C side has copied them.
  subroutine cup_lcs_create_dense(A, B, C, E, F, G, Pdiag, L, ierr, pb_tol, errmsg)
    real(c_double), intent(in) :: A(:, :), B(:, :), C(:, :), E(:, :), G(:, :)
    real(c_double), intent(in), target, contiguous :: F(:), Pdiag(:)
    type(cup_lcs_t), intent(out) :: L
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: pb_tol
    character(len=*), intent(out), optional :: errmsg
    type(cup_csc_matrix), target :: cA, cB, cC, cE, cG
    type(cup_lcs_desc) :: d
    integer :: n, m, p
    character(len=200) :: msg
    m = size(C, 1)
    n = size(C, 2)
    p = 0
    if (size(E) > 0) p = size(E, 2)
    if (size(G) > 0) p = size(G, 2)
    if (.not. shape_ok('A', A, n, n)) return
    if (.not. shape_ok('B', B, n, m)) return
    if (.not. shape_ok('E', E, n, p)) return
    if (.not. shape_ok('G', G, m, p)) return
    if (size(F) /= 0 .and. size(F) /= m) then
      call size_fail('LCS: F', size(F), m, ierr, errmsg)
      return
    end if
    if (size(Pdiag) /= 0 .and. size(Pdiag) /= n) then
      call size_fail('LCS: Pdiag', size(Pdiag), n, ierr, errmsg)
      return
    end if
    d%n = int(n, c_int)
    d%m = int(m, c_int)
    d%p = int(p, c_int)
    call cup_csc_from_dense(C, cC, ierr)
    d%C = cup_csc_view(cC)
    if (size(A) > 0) then
      call cup_csc_from_dense(A, cA, ierr)
      d%A = cup_csc_view(cA)
    end if
    if (size(B) > 0) then
      call cup_csc_from_dense(B, cB, ierr)
      d%B = cup_csc_view(cB)
    end if
    if (size(E) > 0) then
      call cup_csc_from_dense(E, cE, ierr)
      d%E = cup_csc_view(cE)
    end if
    if (size(G) > 0) then
      call cup_csc_from_dense(G, cG, ierr)
      d%G = cup_csc_view(cG)
    end if
    if (size(F) > 0) d%F = c_loc(F)
    if (size(Pdiag) > 0) then
      d%metric%kind = CUP_METRIC_DIAGONAL
      d%metric%diag = c_loc(Pdiag)
    end if
    if (present(pb_tol)) d%pb_tol = pb_tol
    call cup_lcs_create(L, d, ierr, errmsg)
  contains
    logical function shape_ok(name, X, nr, nc)
      character(len=*), intent(in) :: name
      real(c_double), intent(in) :: X(:, :)
      integer, intent(in) :: nr, nc
      shape_ok = size(X) == 0 .or. (size(X, 1) == nr .and. size(X, 2) == nc)
      if (.not. shape_ok) then
        write(msg, '(a,a,i0,a,i0,a,i0,a,i0)') name, ' is ', size(X, 1), ' x ', size(X, 2), &
          ', expected ', nr, ' x ', nc
        call cup_fail_(CUP_ERR_DIM, 'LCS: ' // trim(msg), ierr, errmsg)
      end if
    end function shape_ok
  end subroutine cup_lcs_create_dense

  !> The paper's circuit (Sec. 7) from its parameters.
  subroutine cup_lcs_circuit(L, c, ierr, errmsg)
    type(cup_lcs_t), intent(out) :: L
    type(cup_circuit), intent(in) :: c
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_lcs_circuit(L%ptr, c, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_lcs_circuit

  subroutine cup_lcs_free(L)
    type(cup_lcs_t), intent(inout) :: L
    if (.not. L%borrowed) call c_cup_lcs_free(L%ptr)
    L%ptr = c_null_ptr
    L%borrowed = .false.
  end subroutine cup_lcs_free

  integer function cup_lcs_dim(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_dim = int(c_cup_lcs_dim(L%ptr))
  end function cup_lcs_dim

  integer function cup_lcs_rows(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_rows = int(c_cup_lcs_rows(L%ptr))
  end function cup_lcs_rows

  integer function cup_lcs_inputs(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_inputs = int(c_cup_lcs_inputs(L%ptr))
  end function cup_lcs_inputs

  !> The set {x : C x + F >= 0} with metric P, owned by L (a borrowed handle).
  function cup_lcs_polyset(L) result(K)
    type(cup_lcs_t), intent(in) :: L
    type(cup_polyset_t) :: K
    K%ptr = c_cup_lcs_polyset(L%ptr)
    K%borrowed = .true.
  end function cup_lcs_polyset

  !> .true. if K does not move with u (G absent or zero).
  logical function cup_lcs_fixed_set(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_fixed_set = c_cup_lcs_fixed_set(L%ptr) /= 0
  end function cup_lcs_fixed_set

  ! ---- integrator.h ------------------------------------------------------------------

  !> Parse "n^-2.1", "3e-7", "0.5*n^-1"; CUP_ERR_PARSE with a message otherwise.
  subroutine cup_schedule_parse(spec, s, ierr, errmsg)
    character(len=*), intent(in) :: spec
    type(cup_schedule), intent(out) :: s
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_schedule_parse(cup_f_c_string(spec), s, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_schedule_parse

  real(c_double) function schedule_value_int(s, n)
    type(cup_schedule), intent(in) :: s
    integer, intent(in) :: n
    schedule_value_int = c_cup_schedule_value(s, int(n, c_long))
  end function schedule_value_int

  real(c_double) function schedule_value_long(s, n)
    type(cup_schedule), intent(in) :: s
    integer(c_long), intent(in) :: n
    schedule_value_long = c_cup_schedule_value(s, n)
  end function schedule_value_long

  !> The canonical text of a schedule ("n^-2.1", "1e-06", "0.5*n^-1.05").
  function cup_schedule_format(s) result(text)
    type(cup_schedule), intent(in) :: s
    character(len=:), allocatable :: text
    character(kind=c_char) :: probe(1)
    character(kind=c_char), allocatable :: buf(:)
    integer(c_int) :: n
    n = c_cup_schedule_format(s, probe, 1_c_long)
    allocate(buf(max(n, 0) + 1))
    n = c_cup_schedule_format(s, buf, int(size(buf), c_long))
    text = cup_chars_to_string(buf)
  end function cup_schedule_format

  !> The library's defaults (from the C function).
  subroutine cup_integrator_options_default(o)
    type(cup_integrator_options), intent(out) :: o
    call c_cup_integrator_options_default(o)
  end subroutine cup_integrator_options_default

  !> An integrator for the LCS L with input u (absent: no input). L and u
  !> must outlive it; opt defaults to the library's.
  subroutine cup_integrator_create(integ, L, ierr, u, opt, errmsg)
    type(cup_integrator_t), intent(out) :: integ
    type(cup_lcs_t), intent(in) :: L
    integer, intent(out) :: ierr
    type(cup_input_t), intent(in), optional :: u
    type(cup_integrator_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_integrator_options) :: o
    type(c_ptr) :: up
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (null_fail(L%ptr, 'integrator: LCS', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call c_cup_integrator_options_default(o)
    end if
    up = c_null_ptr
    if (present(u)) up = u%ptr
    cmsg = cup_errbuf_()
    st = c_cup_integrator_create(integ%ptr, L%ptr, up, o, cmsg)
    if (st == CUP_OK) then
      integ%dim = int(c_cup_lcs_dim(L%ptr))
      integ%expected = expected_samples(o)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_integrator_create

  !> Samples a complete run passes to the sink (integrator.h, output kinds).
  pure integer(c_long) function expected_samples(o) result(ns)
    type(cup_integrator_options), intent(in) :: o
    select case (o%output)
    case (CUP_OUTPUT_EVERY)
      ns = o%n / o%output_every + 1
      if (mod(o%n, o%output_every) /= 0) ns = ns + 1
    case (CUP_OUTPUT_SAMPLES)
      ns = o%output_samples
    case (CUP_OUTPUT_FINAL)
      ns = 1
    case default
      ns = 0
    end select
  end function expected_samples

  subroutine cup_integrator_free(integ)
    type(cup_integrator_t), intent(inout) :: integ
    call c_cup_integrator_free(integ%ptr)
    integ%ptr = c_null_ptr
    integ%dim = 0
    integ%expected = 0
  end subroutine cup_integrator_free

  !> Run from x0 (dim entries) over [0, T], passing the selected states to
  !> sink = c_funloc(f) of a bind(C) procedure(cup_sample_fn) with sink_ctx
  !> (c_null_funptr: no sink). ierr = info%status: CUP_OK, a warning, or the
  !> error that stopped the run (info%step, info%t and info%message say where;
  !> errmsg gets the message).
  subroutine cup_integrator_run(integ, x0, sink, sink_ctx, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: x0(:)
    type(c_funptr), value :: sink
    type(c_ptr), value :: sink_ctx
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    type(cup_run_info) :: ri
    if (null_fail(integ%ptr, 'integrator', ierr, errmsg)) return
    if (size(x0) /= integ%dim) then
      call size_fail('x0', size(x0), integ%dim, ierr, errmsg)
      return
    end if
    ierr = int(c_cup_integrator_run(integ%ptr, x0, sink, sink_ctx, ri))
    if (present(info)) info = ri
    if (present(errmsg)) errmsg = cup_chars_to_string(ri%message)
  end subroutine cup_integrator_run

  !> Run from x0 and return the selected samples column-major: t(nsamples),
  !> X(dim, nsamples). On an error the samples before it are kept.
  subroutine cup_integrator_run_store(integ, x0, t, X, nsamples, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: x0(:)
    real(c_double), allocatable, intent(out) :: t(:)
    real(c_double), allocatable, intent(out) :: X(:, :)
    integer, intent(out) :: nsamples
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    type(store_t), target :: s
    type(cup_run_info) :: ri
    integer :: cap, ist
    nsamples = 0
    allocate(t(0), X(max(integ%dim, 0), 0))
    if (null_fail(integ%ptr, 'integrator', ierr, errmsg)) return
    if (size(x0) /= integ%dim) then
      call size_fail('x0', size(x0), integ%dim, ierr, errmsg)
      return
    end if
    s%dim = integ%dim
    cap = int(min(max(integ%expected, 1_c_long), int(huge(cap), c_long)))
    allocate(s%t(cap), s%X(s%dim, cap), stat=ist)
    if (ist /= 0) then                  ! too large at once: let it grow instead
      cap = 1024
      allocate(s%t(cap), s%X(s%dim, cap))
    end if
    ierr = int(c_cup_integrator_run(integ%ptr, x0, c_funloc(store_sink), c_loc(s), ri))
    if (s%nomem) then
      ierr = CUP_ERR_NOMEM
      ri%status = CUP_ERR_NOMEM
      call set_message(ri, 'out of memory storing the trajectory in Fortran arrays')
    end if
    nsamples = s%count
    deallocate(t, X)
    if (size(s%t) == nsamples) then
      call move_alloc(s%t, t)
      call move_alloc(s%X, X)
    else
      allocate(t(nsamples), X(s%dim, nsamples))
      t = s%t(1:nsamples)
      X = s%X(:, 1:nsamples)
    end if
    if (present(info)) info = ri
    if (present(errmsg)) errmsg = cup_chars_to_string(ri%message)
  end subroutine cup_integrator_run_store

  subroutine set_message(ri, text)
    type(cup_run_info), intent(inout) :: ri
    character(len=*), intent(in) :: text
    integer :: i, n
    n = min(len(text), size(ri%message) - 1)
    do i = 1, n
      ri%message(i) = text(i:i)
    end do
    ri%message(n + 1:) = char(0)
  end subroutine set_message

  !> The sink of cup_integrator_run_store: append (t, x) to the store_t at ctx.
  function store_sink(k, t, x, ctx) result(stat) bind(C)
    integer(c_long), value :: k
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(store_t), pointer :: s
    real(c_double), allocatable :: t2(:), X2(:, :)
    integer :: cap, ist
    call c_f_pointer(ctx, s)
    if (s%count == size(s%t)) then
      cap = max(2 * size(s%t), 16)
      allocate(t2(cap), X2(s%dim, cap), stat=ist)
      if (ist /= 0) then
        s%nomem = .true.
        stat = 1
        return
      end if
      t2(1:s%count) = s%t(1:s%count)
      X2(:, 1:s%count) = s%X(:, 1:s%count)
      call move_alloc(t2, s%t)
      call move_alloc(X2, s%X)
    end if
    s%count = s%count + 1
    s%last_k = k
    s%t(s%count) = t
    s%X(:, s%count) = x(1:s%dim)
    stat = 0
  end function store_sink

  !> Copy the final state of the last run (dim entries) into x.
  subroutine cup_integrator_state(integ, x, ierr)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(inout) :: x(:)
    integer, intent(out) :: ierr
    logical :: found
    if (null_fail(integ%ptr, 'integrator', ierr)) return
    if (size(x) /= integ%dim) then
      call size_fail('x', size(x), integ%dim, ierr)
      return
    end if
    call copy_out(c_cup_integrator_state(integ%ptr), integ%dim, x, found, ierr)
  end subroutine cup_integrator_state

  function cup_scheme_name(scheme) result(s)
    integer, intent(in) :: scheme
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_scheme_name(int(scheme, c_int)))
  end function cup_scheme_name

  !> A name of CUP_SCHEME_LIST ("explicit", "implicit", "exponential", "theta") -> CUP_SCHEME_*;
  !> -1 if unknown.
  integer function cup_scheme_parse(name)
    character(len=*), intent(in) :: name
    cup_scheme_parse = int(c_cup_scheme_parse(cup_f_c_string(name)))
  end function cup_scheme_parse

  function cup_output_name(output) result(s)
    integer, intent(in) :: output
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_output_name(int(output, c_int)))
  end function cup_output_name

  !> "every", "samples", "final", "none" -> CUP_OUTPUT_*; -1 if unknown.
  integer function cup_output_parse(name)
    character(len=*), intent(in) :: name
    cup_output_parse = int(c_cup_output_parse(cup_f_c_string(name)))
  end function cup_output_parse

  function cup_wave_name(kind) result(s)
    integer, intent(in) :: kind
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_wave_name(int(kind, c_int)))
  end function cup_wave_name

  !> "constant", "sine", "square", "pwl" -> CUP_WAVE_*; -1 if unknown.
  integer function cup_wave_parse(name)
    character(len=*), intent(in) :: name
    cup_wave_parse = int(c_cup_wave_parse(cup_f_c_string(name)))
  end function cup_wave_parse

  !> info%message as a Fortran string.
  function cup_run_info_message(info) result(s)
    type(cup_run_info), intent(in) :: info
    character(len=:), allocatable :: s
    s = cup_chars_to_string(info%message)
  end function cup_run_info_message
end module catchup_core
