! catchup_pss -- Fortran wrappers of include/catchup/pss.h: the periodic
! steady state by Newton's method on the period map, its Floquet
! multipliers, and measurements of one period (docs/steady-state.md).
! Re-exported by module `catchup`. Conventions as in catchup_base: ierr last
! among the required arguments, errmsg optional after it; a trajectory's
! samples are columns (x(:, k) the state at t(k)).
module catchup_pss
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_funptr, c_null_ptr, c_null_char, &
    c_associated, c_f_pointer, c_loc
  use catchup_constants
  use catchup_types
  use catchup_c, only: c_cup_lcs_dim, c_cup_integrator_options_default
  use catchup_base
  implicit none
  private
  public :: cup_pss_options, cup_pss_info, cup_measure, cup_pss_t, &
    cup_pss_options_default, cup_input_period, cup_input_period_fits, cup_pss_solve, cup_pss_solve_map, cup_pss_free, &
    cup_pss_get_info, cup_pss_x0, cup_pss_residuals, cup_pss_monodromy, cup_pss_multipliers, &
    cup_pss_trajectory, cup_pss_jumps, cup_measure_period, cup_measure_period_jumps, cup_pss_info_message, &
    cup_netlist_element_nodes, &
    cup_netlist_steady_state, cup_input_steady_phase, cup_netlist_set_time_origin

  !> cup_pss_options (pss.h): fields as in C
  type, bind(C) :: cup_pss_options
    real(c_double) :: period = 0        !< T, or 0: the input's common period
    integer(c_int) :: max_iter = 20
    real(c_double) :: tol = 1e-10_c_double
    real(c_double) :: tol_floor = 1e-9_c_double
    real(c_double) :: map_tol = 1e-12_c_double
    real(c_double) :: fd_step = 1e-6_c_double
    integer(c_int) :: warmup_periods = 0
    integer(c_long) :: samples = 0
    integer(c_int) :: jacobian = 0      !< CUP_PSS_JACOBIAN_AUTO (exact where it can) or _FD
  end type cup_pss_options

  !> cup_pss_info (pss.h); the message by cup_pss_info_message(info)
  type, bind(C) :: cup_pss_info
    integer(c_int) :: status = 0
    integer(c_int) :: n = 0
    integer(c_int) :: m = 0
    integer(c_int) :: iterations = 0
    real(c_double) :: period = 0
    real(c_double) :: residual = 0
    real(c_double) :: max_multiplier = 0
    integer(c_long) :: period_runs = 0
    integer(c_long) :: events = 0
    integer(c_long) :: samples = 0
    real(c_double) :: seconds = 0
    character(kind=c_char) :: message(CUP_RUN_MSG_LEN) = c_null_char
    real(c_double) :: t0 = 0          !< the phase: x0 is the state at t0 (cup_input_steady_phase)
    integer(c_long) :: jumps = 0      !< cup_pss_jumps' count; -1: more than 4 a sample + 64, none given
  end type cup_pss_info

  !> cup_measure (pss.h)
  type, bind(C) :: cup_measure
    real(c_double) :: avg = 0, rms = 0, min = 0, max = 0, pp = 0, thd = 0
  end type cup_measure

  !> A solve's result (free with cup_pss_free)
  type :: cup_pss_t
    type(c_ptr) :: ptr = c_null_ptr
  end type cup_pss_t

  ! The raw bind(C) interfaces c_<C name>, generated from the headers at build time (gen_bindings.py)
  include "bind_pss.inc"
  include "bind_netlist.inc"

contains

  subroutine cup_pss_options_default(o)
    type(cup_pss_options), intent(out) :: o
    call c_cup_pss_options_default(o)
  end subroutine cup_pss_options_default

  !> The common period of u's waveforms; CUP_ERR_ARG naming the term without one.
  subroutine cup_input_period(u, T, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(out) :: T
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    T = 0
    cmsg = cup_errbuf_()
    st = c_cup_input_period(u%ptr, T, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_period

  !> CUP_OK if T is a whole number of u's common periods (or u tells none).
  subroutine cup_input_period_fits(u, T, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: T
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_input_period_fits(u%ptr, T, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_period_fits

  !> The steady state's period T (period: the one asked for, or 0: the
  !> sources') and phase t0, the least time from which every source repeats (pss.h).
  subroutine cup_input_steady_phase(u, period, T, t0, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: period
    real(c_double), intent(out) :: T, t0
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    T = 0
    t0 = 0
    cmsg = cup_errbuf_()
    st = c_cup_input_steady_phase(u%ptr, period, T, t0, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_steady_phase

  !> The netlist's sources read from t0 on (netlist.h): make integrators after.
  subroutine cup_netlist_set_time_origin(nl, t0, ierr, errmsg)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(in) :: t0
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(nl%ptr, 'netlist', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_netlist_set_time_origin(nl%ptr, t0, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_netlist_set_time_origin

  !> The steady state of L driven by u (pss.h). r holds the result also when
  !> ierr reports a failed solve (cup_pss_get_info says why).
  subroutine cup_pss_solve(r, L, ierr, u, io, x_guess, opt, errmsg)
    type(cup_pss_t), intent(out) :: r
    type(cup_lcs_t), intent(in) :: L
    integer, intent(out) :: ierr
    type(cup_input_t), intent(in), optional :: u
    type(cup_integrator_options), intent(in), optional :: io
    real(c_double), intent(in), target, optional :: x_guess(:)
    type(cup_pss_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_integrator_options) :: iop
    type(cup_pss_options) :: o
    type(c_ptr) :: up, xp
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(L%ptr, 'steady state: LCS', ierr, errmsg)) return
    if (present(io)) then
      iop = io
    else
      call c_cup_integrator_options_default(iop)
      iop%scheme = CUP_SCHEME_ADAPTIVE
    end if
    if (present(opt)) then
      o = opt
    else
      call c_cup_pss_options_default(o)
    end if
    up = c_null_ptr
    if (present(u)) up = u%ptr
    xp = c_null_ptr
    if (present(x_guess)) then
      if (size(x_guess) /= int(c_cup_lcs_dim(L%ptr))) then
        call cup_size_fail_('x_guess', size(x_guess), int(c_cup_lcs_dim(L%ptr)), ierr, errmsg)
        return
      end if
      xp = c_loc(x_guess)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_pss_solve(r%ptr, L%ptr, up, iop, xp, o, cmsg)
    call cup_finish_pss_(r, st, cmsg, ierr, errmsg)
  end subroutine cup_pss_solve

  !> The steady state of any period map: integ made with T = period.
  subroutine cup_pss_solve_map(r, integ, period, ierr, x_guess, opt, errmsg)
    type(cup_pss_t), intent(out) :: r
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: period
    integer, intent(out) :: ierr
    real(c_double), intent(in), target, optional :: x_guess(:)
    type(cup_pss_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_pss_options) :: o
    type(c_ptr) :: xp
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(integ%ptr, 'steady state: integrator', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call c_cup_pss_options_default(o)
    end if
    xp = c_null_ptr
    if (present(x_guess)) then
      if (size(x_guess) /= integ%dim) then
        call cup_size_fail_('x_guess', size(x_guess), integ%dim, ierr, errmsg)
        return
      end if
      xp = c_loc(x_guess)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_pss_solve_map(r%ptr, integ%ptr, int(integ%dim, c_int), period, xp, o, cmsg)
    call cup_finish_pss_(r, st, cmsg, ierr, errmsg)
  end subroutine cup_pss_solve_map

  !> A solve's status into ierr; its message is the result's when there is one.
  subroutine cup_finish_pss_(r, st, cmsg, ierr, errmsg)
    type(cup_pss_t), intent(in) :: r
    integer(c_int), intent(in) :: st
    character(kind=c_char), intent(in) :: cmsg(:)
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    type(cup_pss_info) :: info
    if (.not. c_associated(r%ptr)) then
      call cup_finish_(st, cmsg, ierr, errmsg)
      return
    end if
    call c_cup_pss_get_info(r%ptr, info)
    ierr = int(st)
    if (present(errmsg)) errmsg = cup_chars_to_string(info%message)
  end subroutine cup_finish_pss_

  subroutine cup_pss_free(r)
    type(cup_pss_t), intent(inout) :: r
    call c_cup_pss_free(r%ptr)
  end subroutine cup_pss_free

  subroutine cup_pss_get_info(r, info)
    type(cup_pss_t), intent(in) :: r
    type(cup_pss_info), intent(out) :: info
    if (c_associated(r%ptr)) call c_cup_pss_get_info(r%ptr, info)
  end subroutine cup_pss_get_info

  function cup_pss_info_message(info) result(s)
    type(cup_pss_info), intent(in) :: info
    character(len=:), allocatable :: s
    s = cup_chars_to_string(info%message)
  end function cup_pss_info_message

  !> The steady state x0 (n entries).
  subroutine cup_pss_x0(r, x0, ierr)
    type(cup_pss_t), intent(in) :: r
    real(c_double), allocatable, intent(out) :: x0(:)
    integer, intent(out) :: ierr
    type(cup_pss_info) :: info
    real(c_double), pointer :: v(:)
    allocate(x0(0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    call c_cup_pss_get_info(r%ptr, info)
    call c_f_pointer(c_cup_pss_x0(r%ptr), v, [info%n])
    x0 = v
    ierr = CUP_OK
  end subroutine cup_pss_x0

  !> ||Phi(x_k) - x_k||_inf, k = 0 .. iterations.
  subroutine cup_pss_residuals(r, res, ierr)
    type(cup_pss_t), intent(in) :: r
    real(c_double), allocatable, intent(out) :: res(:)
    integer, intent(out) :: ierr
    type(cup_pss_info) :: info
    real(c_double), pointer :: v(:)
    allocate(res(0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    call c_cup_pss_get_info(r%ptr, info)
    call c_f_pointer(c_cup_pss_residuals(r%ptr), v, [info%iterations + 1])
    res = v
    ierr = CUP_OK
  end subroutine cup_pss_residuals

  !> The monodromy matrix (n x n); CUP_ERR_ARG if none was computed.
  subroutine cup_pss_monodromy(r, J, ierr)
    type(cup_pss_t), intent(in) :: r
    real(c_double), allocatable, intent(out) :: J(:, :)
    integer, intent(out) :: ierr
    type(cup_pss_info) :: info
    real(c_double), pointer :: v(:, :)
    type(c_ptr) :: p
    allocate(J(0, 0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    call c_cup_pss_get_info(r%ptr, info)
    p = c_cup_pss_monodromy(r%ptr)
    ierr = CUP_ERR_ARG
    if (.not. c_associated(p)) return
    call c_f_pointer(p, v, [info%n, info%n])
    J = v
    ierr = CUP_OK
  end subroutine cup_pss_monodromy

  !> The Floquet multipliers, by decreasing modulus.
  subroutine cup_pss_multipliers(r, mu, ierr)
    type(cup_pss_t), intent(in) :: r
    complex(c_double), allocatable, intent(out) :: mu(:)
    integer, intent(out) :: ierr
    type(cup_pss_info) :: info
    real(c_double), allocatable :: re(:), im(:)
    allocate(mu(0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    call c_cup_pss_get_info(r%ptr, info)
    allocate(re(max(info%n, 1)), im(max(info%n, 1)))
    ierr = int(c_cup_pss_multipliers(r%ptr, re, im))
    if (ierr /= CUP_OK) return
    mu = cmplx(re(1:info%n), im(1:info%n), c_double)
  end subroutine cup_pss_multipliers

  !> One period of the steady state: t(k), x(:, k), zeta(:, k), k = 1 .. samples.
  subroutine cup_pss_trajectory(r, t, x, ierr, zeta)
    type(cup_pss_t), intent(in) :: r
    real(c_double), allocatable, target, intent(out) :: t(:), x(:, :)
    integer, intent(out) :: ierr
    real(c_double), allocatable, target, intent(out), optional :: zeta(:, :)
    type(cup_pss_info) :: info
    type(c_ptr) :: zp
    allocate(t(0), x(0, 0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    call c_cup_pss_get_info(r%ptr, info)
    ierr = CUP_ERR_ARG
    if (info%samples < 1) return
    deallocate(t, x)
    allocate(t(info%samples), x(info%n, info%samples))
    zp = c_null_ptr
    if (present(zeta)) then
      allocate(zeta(max(info%m, 1), info%samples))
      zp = c_loc(zeta)
    end if
    ierr = int(c_cup_pss_trajectory(r%ptr, c_loc(t), c_loc(x), zp))
  end subroutine cup_pss_trajectory

  !> The times in the trajectory's period (on its samples' clock, sorted) at
  !> which a signal may jump (sources' breaks, the adaptive scheme's events);
  !> none with no trajectory, or more than 4 a sample + 64 (info%jumps = -1; pss.h).
  subroutine cup_pss_jumps(r, t, ierr)
    type(cup_pss_t), intent(in) :: r
    real(c_double), allocatable, target, intent(out) :: t(:)
    integer, intent(out) :: ierr
    integer(c_long) :: nj
    allocate(t(0))
    if (cup_null_fail_(r%ptr, 'steady state', ierr)) return
    nj = c_cup_pss_jumps(r%ptr, c_null_ptr)
    deallocate(t)
    allocate(t(nj))
    if (nj > 0) nj = c_cup_pss_jumps(r%ptr, c_loc(t))
    ierr = CUP_OK
  end subroutine cup_pss_jumps

  !> The harmonics' outputs of cup_measure_period(_jumps): amp and phase
  !> (each optional, order + 1 entries) as C pointers (NULL when absent);
  !> .false. with ierr set when one has the wrong size.
  logical function harmonics_out_(order, ap, pp, ierr, amp, phase, errmsg) result(ok)
    integer, intent(in) :: order
    type(c_ptr), intent(out) :: ap, pp
    integer, intent(out) :: ierr
    real(c_double), intent(inout), target, optional :: amp(:), phase(:)
    character(len=*), intent(out), optional :: errmsg
    ok = .false.
    ap = c_null_ptr
    pp = c_null_ptr
    ierr = CUP_OK
    if (present(amp)) then
      if (size(amp) /= order + 1) then
        call cup_size_fail_('amp', size(amp), order + 1, ierr, errmsg)
        return
      end if
      ap = c_loc(amp)
    end if
    if (present(phase)) then
      if (size(phase) /= order + 1) then
        call cup_size_fail_('phase', size(phase), order + 1, ierr, errmsg)
        return
      end if
      pp = c_loc(phase)
    end if
    ok = .true.
  end function harmonics_out_

  !> Measurements of v, sampled uniformly over one period (v(N) closes it);
  !> with amp/phase (order + 1 entries each), its harmonics 0 .. order.
  subroutine cup_measure_period(v, order, m, ierr, amp, phase, errmsg)
    real(c_double), intent(in) :: v(:)
    integer, intent(in) :: order
    type(cup_measure), intent(out) :: m
    integer, intent(out) :: ierr
    real(c_double), intent(out), target, optional :: amp(:), phase(:)
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    type(c_ptr) :: ap, pp
    integer(c_int) :: st
    if (.not. harmonics_out_(order, ap, pp, ierr, amp, phase, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_measure_period(v, int(size(v), c_long), int(order, c_int), m, ap, pp, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_measure_period

  !> cup_measure_period of v sampled at t0 + (k - 1) T / (N - 1), a signal
  !> that jumps at one of jump_t (sorted, in [t0, t0 + T]: cup_pss_jumps)
  !> measured with its jumps at their times (pss.h).
  subroutine cup_measure_period_jumps(v, jump_t, t0, T, order, m, ierr, amp, phase, errmsg)
    real(c_double), intent(in) :: v(:)
    real(c_double), intent(in), target :: jump_t(:)
    real(c_double), intent(in) :: t0, T
    integer, intent(in) :: order
    type(cup_measure), intent(out) :: m
    integer, intent(out) :: ierr
    real(c_double), intent(out), target, optional :: amp(:), phase(:)
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    type(c_ptr) :: ap, pp, jp
    integer(c_int) :: st
    jp = c_null_ptr
    if (.not. harmonics_out_(order, ap, pp, ierr, amp, phase, errmsg)) return
    if (size(jump_t) > 0) jp = c_loc(jump_t)
    cmsg = cup_errbuf_()
    st = c_cup_measure_period_jumps(v, int(size(v), c_long), jp, int(size(jump_t), c_long), t0, T, &
                                    int(order, c_int), m, ap, pp, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_measure_period_jumps

  !> The nodes of a netlist element (a its first, b its second): its power is
  !> v(a,b) i(element). Bound here, beside the power measurements.
  subroutine cup_netlist_element_nodes(nl, element, a, b, ierr, errmsg)
    type(cup_netlist_t), intent(in) :: nl
    character(len=*), intent(in) :: element
    character(len=:), allocatable, intent(out) :: a, b
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    type(c_ptr) :: pa, pb
    integer(c_int) :: st
    a = ''
    b = ''
    if (cup_null_fail_(nl%ptr, 'netlist', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_netlist_element_nodes(nl%ptr, cup_f_c_string(element), pa, pb, cmsg)
    if (st == CUP_OK) then
      a = cup_c_string(pa)
      b = cup_c_string(pb)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_netlist_element_nodes

  !> .options steadystate (steadyperiod=T): .true. if the netlist asks for its
  !> steady state, with the period (0: the sources').
  logical function cup_netlist_steady_state(nl, period) result(asks)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(out) :: period
    period = 0
    asks = .false.
    if (c_associated(nl%ptr)) asks = c_cup_netlist_steady_state(nl%ptr, period) /= 0
  end function cup_netlist_steady_state
end module catchup_pss
