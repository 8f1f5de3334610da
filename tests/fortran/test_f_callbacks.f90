! test_f_callbacks -- Fortran bind(C) callbacks passed with c_funloc and a
! context pointer (c_loc of a Fortran derived type):
!  * u(t) = 16 sin(6 pi t) - 0.5 as a callback gives the built-in sine's
!    trajectory to ~1e-12;
!  * a perturbation f(t, x) = 0 leaves the trajectory unchanged and is called
!    f_order times per step;
!  * an f that fails for t > 0.5 stops the run with CUP_ERR_CALLBACK after 500
!    completed steps (n = 1000, f_order = 1: f is evaluated at midpoints),
!    keeping the 501 samples before;
!  * the per-step callback, a user sink, and a sink that stops the run;
!  * the adaptive scheme with a Fortran event callback: its events are the
!    run's, in time order, and the callback input (interpolated per step)
!    gives the built-in waveform's trajectory within tol.
module callbacks
  use, intrinsic :: iso_c_binding
  use catchup, only: cup_proj_info
  implicit none
  real(c_double), parameter :: pi = 3.14159265358979323846264338327950288_c_double

  type :: sine_par
    real(c_double) :: amplitude = 16, frequency = 3, offset = -0.5_c_double
    integer :: calls = 0
    logical :: fail = .false.
  end type sine_par

  type :: f_par
    integer :: calls = 0
    real(c_double) :: t_fail = huge(1d0)     ! return nonzero for t > t_fail
    real(c_double) :: t_max = -1             ! largest t seen
  end type f_par

  type :: step_par
    integer :: steps = 0
    integer :: bad = 0
  end type step_par

  type :: event_par
    integer :: count = 0
    integer :: bad = 0                       ! out of order, or a row or flag out of range
    real(c_double) :: last_t = -1
  end type event_par

  type :: sink_par
    integer :: count = 0
    integer(c_long) :: stop_at = -1
    real(c_double) :: last(3) = 0
  end type sink_par

contains

  function on_event(t, row, on, ctx) result(stat) bind(C)
    real(c_double), value :: t
    integer(c_int), value :: row, on
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(event_par), pointer :: p
    call c_f_pointer(ctx, p)
    p%count = p%count + 1
    if (t < p%last_t .or. row < 0 .or. row > 1 .or. (on /= 0 .and. on /= 1)) p%bad = p%bad + 1
    p%last_t = t
    stat = 0
  end function on_event

  function sine_u(t, u, ctx) result(stat) bind(C)
    real(c_double), value :: t
    real(c_double), intent(inout) :: u(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(sine_par), pointer :: p
    call c_f_pointer(ctx, p)
    p%calls = p%calls + 1
    u(1) = p%amplitude * sin(2 * pi * p%frequency * t) + p%offset
    stat = merge(1_c_int, 0_c_int, p%fail .and. t > 0.25d0)
  end function sine_u

  function pert_f(t, x, f, ctx) result(stat) bind(C)
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    real(c_double), intent(inout) :: f(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(f_par), pointer :: p
    call c_f_pointer(ctx, p)
    p%calls = p%calls + 1
    p%t_max = max(p%t_max, t)
    f(1:3) = 0 * x(1:3)
    stat = merge(1_c_int, 0_c_int, t > p%t_fail)
  end function pert_f

  function on_step(k, t, pinfo, ctx) result(stat) bind(C)
    integer(c_long), value :: k
    real(c_double), value :: t
    type(cup_proj_info), intent(in) :: pinfo
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(step_par), pointer :: p
    call c_f_pointer(ctx, p)
    p%steps = p%steps + 1
    if (k /= p%steps .or. pinfo%status < 0 .or. t <= 0) p%bad = p%bad + 1
    stat = 0
  end function on_step

  function user_sink(k, t, x, ctx) result(stat) bind(C)
    integer(c_long), value :: k
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(sink_par), pointer :: p
    call c_f_pointer(ctx, p)
    p%count = p%count + 1
    p%last = x(1:3)
    stat = merge(1_c_int, 0_c_int, k == p%stop_at .and. t >= 0)
  end function user_sink
end module callbacks

program test_f_callbacks
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  use callbacks
  implicit none
  integer, parameter :: n = 1000
  type(cup_lcs_t) :: lcs
  type(cup_input_t) :: u_builtin, u_callback
  type(cup_integrator_options) :: opt
  type(cup_run_info) :: info
  type(sine_par), target :: spar
  type(f_par), target :: fpar
  type(step_par), target :: stpar
  type(sink_par), target :: skpar
  type(event_par), target :: evpar
  real(c_double), allocatable :: t0(:), X0(:, :), t1(:), X1(:, :)
  real(c_double) :: d
  integer :: ierr, ns0, ns1
  character(len=CUP_ERRMSG_LEN) :: msg

  call cup_lcs_circuit(lcs, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr)
  call cup_input_create(u_builtin, 1, ierr)
  call cup_input_add_sine(u_builtin, 1, 16d0, 3d0, ierr)
  call cup_input_add_constant(u_builtin, 1, -0.5d0, ierr)
  call cup_input_create(u_callback, 1, ierr)
  call cup_input_set_callback(u_callback, c_funloc(sine_u), c_loc(spar), 1d-14, 1d-13, ierr)
  call check_int(ierr, CUP_OK, 'set the Fortran input callback')
  call check(.not. cup_input_is_constant(u_callback), 'a callback input is not constant')

  call cup_integrator_options_default(opt)
  opt%n = n
  opt%eps = cup_schedule(0, 0)                 ! exact projections
  opt%eta = cup_schedule(0, 0)

  call section('input callback = built-in sine')
  call run(u_builtin, opt, t0, X0, ns0, ierr, info)
  call check(ierr == CUP_OK .and. ns0 == n + 1, 'built-in run')
  call run(u_callback, opt, t1, X1, ns1, ierr, info)
  call check(ierr == CUP_OK .and. ns1 == n + 1, 'callback run')
  call check(spar%calls > n, 'the callback was called (context counts the calls)')
  if (ns0 == ns1) then
    d = maxval(abs(X1 - X0))
    write(*, '(a,es10.3,a,i0,a)') 'max |X_callback - X_builtin| = ', d, ' (', spar%calls, ' calls)'
    call check(d <= 1d-12, 'callback trajectory within 1e-12 of the built-in one')
  end if

  call section('perturbation f = 0')
  opt%f = c_funloc(pert_f)
  opt%f_ctx = c_loc(fpar)
  call run(u_builtin, opt, t1, X1, ns1, ierr, info)
  call check(ierr == CUP_OK .and. ns1 == n + 1, 'run with f = 0')
  call check_int(fpar%calls, 3 * n, 'f called f_order = 3 times per step')
  if (ns1 == ns0) call check(maxval(abs(X1 - X0)) == 0, 'f = 0 leaves the trajectory unchanged')

  call section('perturbation failing for t > 0.5')
  fpar = f_par(t_fail=0.5d0)
  opt%f_order = 1
  call run(u_builtin, opt, t1, X1, ns1, ierr, info, msg)
  call check_int(ierr, CUP_ERR_CALLBACK, 'ierr = CUP_ERR_CALLBACK')
  call check_int(int(info%status), CUP_ERR_CALLBACK, 'info%status')
  call check_int(int(info%step), 500, 'info%step = 500')
  call check_close(info%t, 0.5d0, 1d-15, 'info%t = t_500')
  call check_int(ns1, 501, 'the 501 samples before the failure are kept')
  if (ns1 == 501) call check(maxval(abs(X1 - X0(:, 1:501))) == 0, 'and equal the unperturbed ones')
  call check_contains(msg, 'step 501', 'message says where')
  call check_close(fpar%t_max, 0.5005d0, 1d-12, 'f_order = 1 evaluates f at the midpoint')

  call section('per-step callback and user sink')
  opt%f = c_null_funptr
  opt%f_ctx = c_null_ptr
  opt%f_order = 3
  opt%on_step = c_funloc(on_step)
  opt%step_ctx = c_loc(stpar)
  call run_sink(opt, ierr, info)
  call check(ierr == CUP_OK, 'run with on_step and a user sink')
  call check_int(stpar%steps, n, 'on_step called once per step')
  call check_int(stpar%bad, 0, 'on_step saw k = 1..n, t > 0, projection status >= 0')
  call check_int(skpar%count, n + 1, 'user sink saw n + 1 states')
  call check(all(skpar%last == X0(:, n + 1)), 'user sink saw the final state')
  skpar = sink_par(stop_at=10)
  opt%on_step = c_null_funptr
  call run_sink(opt, ierr, info)
  call check_int(ierr, CUP_ERR_INTERRUPTED, 'a sink returning nonzero interrupts')
  call check_int(int(info%step), 10, 'interrupted at step 10')

  call section('adaptive scheme: event callback, callback input')
  spar = sine_par()
  fpar = f_par()
  opt%f = c_null_funptr
  opt%f_order = 3
  opt%scheme = CUP_SCHEME_ADAPTIVE
  opt%tol_abs = 1d-8
  opt%tol_rel = 1d-8
  opt%output = CUP_OUTPUT_SAMPLES
  opt%output_samples = 101
  opt%on_event = c_funloc(on_event)
  opt%event_ctx = c_loc(evpar)
  call run(u_builtin, opt, t0, X0, ns0, ierr, info)
  call check(ierr == CUP_OK .and. ns0 == 101, 'adaptive run, built-in input')
  call check(evpar%count == info%events .and. evpar%count >= 8 .and. evpar%bad == 0, &
    'the event callback saw the run''s events, in time order')
  call check(info%err_est > 0 .and. info%err_est < 1d-7, 'the run estimates its error below 10 tol')
  opt%on_event = c_null_funptr
  call run(u_callback, opt, t1, X1, ns1, ierr, info)
  call check(ierr == CUP_OK .and. ns1 == 101, 'adaptive run, Fortran callback input')
  if (ns0 == ns1) then
    d = maxval(abs(X1 - X0))
    write(*, '(a,es10.3,a,i0,a,es10.3)') 'adaptive: max |X_callback - X_builtin| = ', d, ' (', spar%calls, &
      ' calls), estimate ', info%err_est
    call check(d <= 2d-7 .and. info%err_est <= 2d-7, 'the two inputs agree within tol (1 + max |x|)')
  end if
  opt%scheme = CUP_SCHEME_EXPLICIT
  opt%output = CUP_OUTPUT_EVERY
  opt%f_order = 1

  call section('failing input callback')
  spar%fail = .true.
  call run(u_callback, opt, t1, X1, ns1, ierr, info, msg)
  call check_int(ierr, CUP_ERR_CALLBACK, 'input callback failure -> CUP_ERR_CALLBACK')
  call check(info%step >= 249 .and. info%step <= 250, 'stopped near t = 0.25: ' // trim(msg))

  call cup_input_free(u_callback)
  call cup_input_free(u_builtin)
  call cup_lcs_free(lcs)
  deallocate(t0, X0, t1, X1)    ! main-program allocatables are not freed at exit (valgrind)
  call finish()

contains

  subroutine run(u, opt, t, X, ns, ierr, info, msg)
    type(cup_input_t), intent(in) :: u
    type(cup_integrator_options), intent(in) :: opt
    real(c_double), allocatable, intent(out) :: t(:), X(:, :)
    integer, intent(out) :: ns, ierr
    type(cup_run_info), intent(out) :: info
    character(len=*), intent(out), optional :: msg
    type(cup_integrator_t) :: integ
    call cup_integrator_create(integ, lcs, ierr, u=u, opt=opt, errmsg=msg)
    call check_int(ierr, CUP_OK, 'integrator create')
    call cup_integrator_run_store(integ, [0d0, 0d0, 0d0], t, X, ns, ierr, info, msg)
    call cup_integrator_free(integ)
  end subroutine run

  subroutine run_sink(opt, ierr, info)
    type(cup_integrator_options), intent(in) :: opt
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out) :: info
    type(cup_integrator_t) :: integ
    call cup_integrator_create(integ, lcs, ierr, u=u_builtin, opt=opt)
    call cup_integrator_run(integ, [0d0, 0d0, 0d0], c_funloc(user_sink), c_loc(skpar), ierr, info)
    call cup_integrator_free(integ)
  end subroutine run_sink
end program test_f_callbacks
