! test_f_case1 -- the paper's case 1 through the Fortran API:
!  * the trajectory equals the one the C API gives for the same problem (a C
!    helper linked into this test calls the C functions directly), every
!    sample to 1e-14, for the paper's tolerances and exact projections;
!  * with exact projections at n = 10^3 the max-norm error against the
!    Richardson reference (tests/data) is within 2% of 1.52/n (docs/design.md);
!  * the paper's tolerances eps_n = n^-2.1, eta_n = n^-1.05 are certified and
!    change the trajectory by < 1% of the discretization error.
!
!   test_f_case1 DATA_DIR      (tests/data: the reference limits)
program test_f_case1
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  implicit none

  interface
    function cupt_case1_c(n, eps, eta, t, X, count) bind(C, name="cupt_case1_c") result(st)
      import :: c_long, c_char, c_double, c_int
      integer(c_long), value :: n
      character(kind=c_char), intent(in) :: eps(*), eta(*)
      real(c_double), intent(inout) :: t(*), X(*)
      integer(c_long), intent(out) :: count
      integer(c_int) :: st
    end function cupt_case1_c
  end interface

  character(len=1024) :: datadir
  real(c_double) :: ref(3, 0:1000)
  real(c_double), allocatable :: te(:), Xe(:, :), tp(:), Xp(:, :)
  type(cup_run_info) :: info
  real(c_double) :: err, d
  integer :: ierr, ns, n

  if (command_argument_count() < 1) then
    write(*, '(a)') 'usage: test_f_case1 DATA_DIR'
    stop 2
  end if
  call get_command_argument(1, datadir)

  call section('Fortran API = C API, sample by sample')
  call compare_with_c(100, 'n^-2.1', 'n^-1.05')
  call compare_with_c(1000, 'n^-2.1', 'n^-1.05')
  call compare_with_c(1000, '0', '0')

  call section('error against the Richardson reference at n = 1000')
  call load_reference(trim(datadir) // '/ref_case1_limit_richardson.csv', ref)
  n = 1000
  call run_case1(n, '0', '0', te, Xe, ns, ierr, info)          ! exact projections
  call check(ierr == CUP_OK .and. ns == n + 1, 'exact-projection run')
  if (ns == n + 1) then
    err = maxval(abs(Xe - ref))
    write(*, '(a,es12.5,a,f7.4,a)') 'max-norm error ', err, ' = ', err * n, ' / n'
    call check(abs(err * n - 1.52d0) <= 0.02d0 * 1.52d0, 'error within 2% of 1.52/n')
    call check(all(abs(te - grid(n)) <= 1d-16), 't_k = k h on the grid k/1000')
  end if

  call section('paper tolerances n^-2.1, n^-1.05 at n = 1000')
  call run_case1(n, 'n^-2.1', 'n^-1.05', tp, Xp, ns, ierr, info)
  call check(ierr == CUP_OK .and. ns == n + 1, 'paper-tolerance run')
  call check(info%max_eps_cert <= real(n, c_double)**(-2.1d0), 'certified eps <= n^-2.1')
  call check(info%max_eta_cert <= real(n, c_double)**(-1.05d0), 'certified eta <= n^-1.05')
  if (ns == n + 1) then
    d = maxval(abs(Xp - Xe))
    write(*, '(a,es12.5)') 'paper tolerances vs exact: ', d
    call check(d <= 0.01d0 * 1.52d0 / n, 'paper tolerances change the trajectory by < 1% of the error')
  end if
  deallocate(te, Xe, tp, Xp)    ! main-program allocatables are not freed at exit (valgrind)
  call finish()

contains

  function grid(n) result(t)
    integer, intent(in) :: n
    real(c_double) :: t(n + 1)
    integer :: k
    t = [(real(k, c_double) * (1d0 / n), k = 0, n)]
    t(n + 1) = 1
  end function grid

  !> The paper's case 1 through the Fortran API, every step stored.
  subroutine run_case1(n, eps, eta, t, X, ns, ierr, info)
    integer, intent(in) :: n
    character(len=*), intent(in) :: eps, eta
    real(c_double), allocatable, intent(out) :: t(:), X(:, :)
    integer, intent(out) :: ns, ierr
    type(cup_run_info), intent(out) :: info
    type(cup_lcs_t) :: lcs
    type(cup_input_t) :: u
    type(cup_integrator_options) :: opt
    type(cup_integrator_t) :: integ
    character(len=CUP_ERRMSG_LEN) :: msg
    call cup_lcs_circuit(lcs, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr, msg)
    call check_int(ierr, CUP_OK, 'circuit: ' // trim(msg))
    call cup_input_create(u, 1, ierr)
    call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
    call cup_input_add_constant(u, 1, -0.5d0, ierr)
    call cup_integrator_options_default(opt)
    opt%n = n
    opt%T = 1
    call cup_schedule_parse(eps, opt%eps, ierr)
    call cup_schedule_parse(eta, opt%eta, ierr)
    call cup_integrator_create(integ, lcs, ierr, u=u, opt=opt, errmsg=msg)
    call check_int(ierr, CUP_OK, 'integrator: ' // trim(msg))
    call cup_integrator_run_store(integ, [0d0, 0d0, 0d0], t, X, ns, ierr, info)
    call cup_integrator_free(integ)
    call cup_input_free(u)
    call cup_lcs_free(lcs)
  end subroutine run_case1

  subroutine compare_with_c(n, eps, eta)
    integer, intent(in) :: n
    character(len=*), intent(in) :: eps, eta
    real(c_double), allocatable :: t(:), X(:, :), tc(:), Xc(:, :)
    integer(c_long) :: count
    integer :: ns, ierr, stc
    type(cup_run_info) :: info
    character(len=80) :: tag
    write(tag, '(a,i0,a,a,a,a)') 'n = ', n, ', eps ', eps, ', eta ', eta
    allocate(tc(n + 1), Xc(3, n + 1))
    stc = cupt_case1_c(int(n, c_long), eps // c_null_char, eta // c_null_char, tc, Xc, count)
    call run_case1(n, eps, eta, t, X, ns, ierr, info)
    call check(stc == CUP_OK .and. ierr == CUP_OK, 'both runs succeed, ' // trim(tag))
    call check(ns == n + 1 .and. count == n + 1, 'n + 1 samples each, ' // trim(tag))
    if (ns == n + 1 .and. count == n + 1) then
      call check(all(t == tc), 'same times, ' // trim(tag))
      write(*, '(a,a,es10.3)') trim(tag), ': max |X_Fortran - X_C| = ', maxval(abs(X - Xc))
      call check(maxval(abs(X - Xc)) <= 1d-14, 'every sample within 1e-14 of C, ' // trim(tag))
    end if
  end subroutine compare_with_c

  subroutine load_reference(path, ref)
    character(len=*), intent(in) :: path
    real(c_double), intent(out) :: ref(3, 0:1000)
    real(c_double) :: t
    integer :: unit, ios, k
    character(len=64) :: header
    ref = 0
    open(newunit=unit, file=path, status='old', action='read', iostat=ios)
    call check(ios == 0, 'open ' // path)
    if (ios /= 0) return
    read(unit, '(a)') header
    call check(trim(header) == 't,x1,x2,x3', 'reference header')
    do k = 0, 1000
      read(unit, *, iostat=ios) t, ref(:, k)
      if (ios /= 0) exit
      if (abs(t - k / 1000d0) > 1d-15) ios = -99
      if (ios /= 0) exit
    end do
    call check(ios == 0, 'reference has rows t = k/1000, k = 0..1000')
    close(unit)
  end subroutine load_reference
end program test_f_case1
