! paper_case1 -- the paper's case 1 through the Fortran API: the circuit
! R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, u = 16 sin(6 pi t) - 0.5 (a sine term
! of amplitude 16 and frequency 3 plus a constant -0.5), x0 = 0, T = 1,
! eps_n = n^-2.1, eta_n = n^-1.05. Writes /t and /x (and the attributes of
! the run) to an HDF5 file through module catchup_h5run, like catchup-run,
! and prints the final state.
!
!   paper_case1 [n [OUT.h5]]          (default: n = 100, paper_case1.h5)
program paper_case1
  use, intrinsic :: iso_c_binding, only: c_double, c_long
  use, intrinsic :: iso_fortran_env, only: int64
  use catchup
  use catchup_h5run
  implicit none
  character(len=*), parameter :: eps_spec = 'n^-2.1', eta_spec = 'n^-1.05'
  type(cup_lcs_t) :: lcs
  type(cup_input_t) :: u
  type(cup_integrator_options) :: opt
  type(cup_integrator_t) :: integ
  type(cup_h5run_t) :: out
  type(cup_run_info) :: info
  character(len=CUP_ERRMSG_LEN) :: msg
  character(len=512) :: path
  character(len=32) :: arg
  real(c_double) :: x(3)
  integer :: n, ierr, run_status
  integer(int64) :: c0, c1, rate

  n = 100
  path = 'paper_case1.h5'
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    read(arg, *) n
  end if
  if (command_argument_count() >= 2) call get_command_argument(2, path)

  call cup_lcs_circuit(lcs, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr, msg)
  call stop_on(ierr, 'circuit', msg)
  call cup_input_create(u, 1, ierr, msg)
  call stop_on(ierr, 'input', msg)
  call cup_input_add_sine(u, 1, 16d0, 3d0, ierr, errmsg=msg)       ! component 1
  call stop_on(ierr, 'input', msg)
  call cup_input_add_constant(u, 1, -0.5d0, ierr, msg)
  call stop_on(ierr, 'input', msg)

  call cup_integrator_options_default(opt)
  opt%n = n
  opt%T = 1
  call cup_schedule_parse(eps_spec, opt%eps, ierr, msg)
  call stop_on(ierr, 'eps', msg)
  call cup_schedule_parse(eta_spec, opt%eta, ierr, msg)
  call stop_on(ierr, 'eta', msg)
  call cup_integrator_create(integ, lcs, ierr, u=u, opt=opt, errmsg=msg)
  call stop_on(ierr, 'integrator', msg)

  call cup_h5run_create(out, path, cup_lcs_dim(lcs), ierr, msg)
  call stop_on(ierr, 'HDF5 output', msg)
  call system_clock(c0, rate)
  call cup_integrator_run_h5(integ, [0d0, 0d0, 0d0], out, ierr, info, msg)
  call system_clock(c1)
  run_status = ierr
  call stop_on(run_status, 'run', msg)

  call cup_h5run_attr(out, 'n', int(n, c_long), ierr)
  call cup_h5run_attr(out, 'T', opt%T, ierr)
  call cup_h5run_attr(out, 'eps', eps_spec, ierr)
  call cup_h5run_attr(out, 'eta', eta_spec, ierr)
  call cup_h5run_attr(out, 'scheme', cup_scheme_name(opt%scheme), ierr)
  call cup_h5run_attr(out, 'catchup_version', cup_version(), ierr)
  call cup_h5run_attr(out, 'status', cup_status_name(run_status), ierr)
  call cup_h5run_attr(out, 'wall_seconds', real(c1 - c0, c_double) / real(rate, c_double), ierr)
  call cup_h5run_attr(out, 'projected', info%projected, ierr)
  call cup_h5run_attr(out, 'skipped', info%skipped, ierr)
  call cup_h5run_attr(out, 'dual_iterations', int(info%dual_iterations, c_long), ierr)
  call cup_h5run_attr(out, 'max_eps_cert', info%max_eps_cert, ierr)
  call cup_h5run_attr(out, 'max_eta_cert', info%max_eta_cert, ierr)
  call stop_on(ierr, 'HDF5 attributes', '')
  call cup_h5run_close(out, ierr, msg)
  call stop_on(ierr, 'HDF5 close', msg)

  call cup_integrator_state(integ, x, ierr)
  write(*, '(a,i0,a,a)') 'paper case 1, n = ', n, ', wrote ', trim(path)
  write(*, '(a,3es24.16)') 'x(T) = ', x

  call cup_integrator_free(integ)
  call cup_input_free(u)
  call cup_lcs_free(lcs)

contains

  subroutine stop_on(ierr, what, msg)
    integer, intent(in) :: ierr
    character(len=*), intent(in) :: what, msg
    if (ierr >= 0) return
    write(*, '(a,a,a,a,a,a)') what, ': ', cup_status_name(ierr), ' (', trim(msg), ')'
    call cup_h5run_free(out)
    error stop 1
  end subroutine stop_on
end program paper_case1
