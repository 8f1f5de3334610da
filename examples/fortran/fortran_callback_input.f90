! fortran_callback_input -- the paper's circuit, case 1 (R1=1, R2=2, R3=1,
! L2=1, L3=2, C4=1; x0 = 0; T = 1), with the input u(t) = 16 sin(6 pi t) - 0.5
! given by a Fortran bind(C) callback. Its parameters reach it through the
! context pointer: c_loc of a Fortran derived type, turned back into a
! Fortran pointer by c_f_pointer inside the callback.
!
!   fortran_callback_input [n]        (n steps, default 100)
module sine_input_mod
  use, intrinsic :: iso_c_binding, only: c_double, c_int, c_ptr, c_f_pointer
  implicit none
  private
  public :: sine_input, sine_u

  !> What the callback needs, and what it tells back.
  type, public :: sine_input
    real(c_double) :: amplitude = 16
    real(c_double) :: frequency = 3      !< cycles per unit time: 16 sin(6 pi t)
    real(c_double) :: offset = -0.5_c_double
    integer :: calls = 0
  end type sine_input

contains

  !> A procedure(cup_input_fn): u(1) = amplitude sin(2 pi frequency t) + offset.
  function sine_u(t, u, ctx) result(stat) bind(C)
    real(c_double), value :: t
    real(c_double), intent(inout) :: u(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    real(c_double), parameter :: pi = 3.14159265358979323846264338327950288_c_double
    type(sine_input), pointer :: par
    call c_f_pointer(ctx, par)
    u(1) = par%amplitude * sin(2 * pi * par%frequency * t) + par%offset
    par%calls = par%calls + 1
    stat = 0
  end function sine_u
end module sine_input_mod

program fortran_callback_input
  use, intrinsic :: iso_c_binding, only: c_double, c_funloc, c_loc
  use catchup
  use sine_input_mod
  implicit none
  type(cup_circuit) :: circuit
  type(cup_lcs_t) :: lcs
  type(cup_input_t) :: u
  type(cup_integrator_options) :: opt
  type(cup_integrator_t) :: integ
  type(cup_run_info) :: info
  type(sine_input), target :: par
  real(c_double), allocatable :: t(:), X(:, :)
  character(len=CUP_ERRMSG_LEN) :: msg
  character(len=32) :: arg
  integer :: n, ns, ierr

  n = 100
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    read(arg, *) n
  end if

  circuit = cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0])
  call cup_lcs_circuit(lcs, circuit, ierr, msg)
  call stop_on(ierr, 'circuit', msg)

  call cup_input_create(u, 1, ierr, msg)
  call stop_on(ierr, 'input', msg)
  call cup_input_set_callback(u, c_funloc(sine_u), c_loc(par), 1e-13_c_double, 1e-12_c_double, ierr)
  call stop_on(ierr, 'input callback', '')

  call cup_integrator_options_default(opt)       ! the library's defaults
  opt%n = n
  opt%T = 1
  call cup_schedule_parse('n^-2.1', opt%eps, ierr)
  call cup_schedule_parse('n^-1.05', opt%eta, ierr)
  call cup_integrator_create(integ, lcs, ierr, u=u, opt=opt, errmsg=msg)
  call stop_on(ierr, 'integrator', msg)

  call cup_integrator_run_store(integ, [0d0, 0d0, 0d0], t, X, ns, ierr, info, msg)
  call stop_on(ierr, 'run', msg)

  write(*, '(a,i0,a,i0,a,i0,a)') 'n = ', n, ': ', ns, ' samples, ', par%calls, ' calls of the Fortran u(t)'
  write(*, '(a,f6.3,a,3es24.16)') 'x(', t(ns), ') = ', X(:, ns)
  write(*, '(a,es10.3,a,es10.3)') 'largest certified eps ', info%max_eps_cert, ', eta ', info%max_eta_cert

  call cup_integrator_free(integ)
  call cup_input_free(u)
  call cup_lcs_free(lcs)
  deallocate(t, X)        ! main-program allocatables are not freed at exit

contains

  subroutine stop_on(ierr, what, msg)
    integer, intent(in) :: ierr
    character(len=*), intent(in) :: what, msg
    if (ierr >= 0) return
    write(*, '(a,a,a,a,a,a)') what, ': ', cup_status_name(ierr), ' (', trim(msg), ')'
    error stop 1
  end subroutine stop_on
end program fortran_callback_input
