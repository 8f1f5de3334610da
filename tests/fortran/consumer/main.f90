! Outside Fortran consumer: `use catchup` from the installed module, the
! module and the library agree on the version, and the paper's case 1 runs.
program consumer_fortran
  use, intrinsic :: iso_c_binding, only: c_double
  use catchup
  implicit none
  type(cup_lcs_t) :: lcs
  type(cup_input_t) :: u
  type(cup_integrator_t) :: integ
  type(cup_integrator_options) :: opt
  real(c_double), allocatable :: t(:), X(:, :)
  integer :: ierr, ns
  if (cup_version() /= CUP_VERSION_STRING) then
    write(*, '(a,a,a,a)') 'module ', CUP_VERSION_STRING, ' but library ', cup_version()
    stop 1
  end if
  call cup_lcs_circuit(lcs, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr)
  call cup_input_create(u, 1, ierr)
  call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
  call cup_input_add_constant(u, 1, -0.5d0, ierr)
  call cup_integrator_options_default(opt)
  call cup_integrator_create(integ, lcs, ierr, u=u, opt=opt)
  call cup_integrator_run_store(integ, [0d0, 0d0, 0d0], t, X, ns, ierr)
  if (ierr /= CUP_OK .or. ns /= 101) stop 2
  write(*, '(a,a,a,3f10.6)') 'consumer_fortran: catchup ', cup_version(), ', x(1) =', X(:, ns)
  call cup_integrator_free(integ)
  call cup_input_free(u)
  call cup_lcs_free(lcs)
end program consumer_fortran
