! test_f_switch -- switches and a controller from Fortran (module catchup):
!  * a netlist with a switch: its count, and the scene's integrator runs it
!    (the adaptive scheme, configurations formed once each);
!  * a bind(C) controller passed with c_funloc writes the buck's PWM every
!    5 us: 80 calls over 400 us, and the final state of the PULSE-gated
!    buck (the same netlist without the controller) to 1e-9.
module switch_gates
  use, intrinsic :: iso_c_binding
  implicit none
  integer :: calls = 0
contains
  integer(c_int) function pwm_gate(t, x, nswitch, gate, ctx) bind(C)
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    integer(c_int), value :: nswitch
    integer(c_int), intent(inout) :: gate(nswitch)
    type(c_ptr), value :: ctx
    calls = calls + 1
    gate(1) = merge(1_c_int, 0_c_int, modulo(nint(t / 5d-6), 4) == 0)
    pwm_gate = 0
    if (x(1) /= x(1) .or. c_associated(ctx)) pwm_gate = 1
  end function pwm_gate
end module switch_gates

program test_f_switch
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  use switch_gates
  implicit none
  integer :: ierr, u
  character(len=CUP_ERRMSG_LEN) :: msg
  real(c_double) :: xa(2), xb(2)

  open(newunit=u, file='f_switch_buck.cir', status='replace', action='write')
  write(u, '(a)') 'ideal buck', 'V1 in 0 12', 'S1 in sw g 0 SMOD', 'D1 0 sw', 'L1 sw out 100u', 'C1 out 0 10u', &
    'R1 out 0 5', 'Vg g 0 PULSE(0 1 0 jump jump 5u 20u)', '.model SMOD SW(VT=0.5)', '.tran 400u 400u'
  close(u)

  call section('switch: the PULSE-gated buck through a scene')
  call run_buck(.false., xa)
  call section('switch: the same PWM from a Fortran controller')
  call run_buck(.true., xb)
  call check_int(calls, 80, 'the controller is called at t = k 5 us, k = 0..79')
  call check_close(xb(1), xa(1), 1d-9, 'i(L1) at 400 us: the controller run against the PULSE run')
  call check_close(xb(2), xa(2), 1d-9, 'v(C1) at 400 us: the controller run against the PULSE run')
  call finish()

contains

  subroutine run_buck(controlled, xf)
    logical, intent(in) :: controlled
    real(c_double), intent(out) :: xf(2)
    type(cup_scene_t) :: s
    type(cup_netlist_t) :: nl
    type(cup_integrator_t) :: integ
    real(c_double), allocatable :: t(:), X(:, :), x0(:)
    integer :: ns
    call cup_scene_load_string(s, 'netlist:' // new_line('a') // '  file: f_switch_buck.cir' // new_line('a'), &
                               'buck.yaml', ierr, dir='.', errmsg=msg)
    call check_int(ierr, CUP_OK, 'scene: ' // trim(msg))
    nl = cup_scene_netlist(s)
    call check_int(cup_netlist_switch_count(nl), 1, 'one switch')
    if (controlled) then
      call cup_netlist_set_controller(nl, 5d-6, c_funloc(pwm_gate), c_null_ptr, ierr, errmsg=msg)
      call check_int(ierr, CUP_OK, 'set the controller: ' // trim(msg))
    end if
    call cup_scene_integrator(s, integ, ierr, errmsg=msg)
    call check_int(ierr, CUP_OK, 'integrator: ' // trim(msg))
    call cup_scene_x0(s, x0, ierr)
    call cup_integrator_run_store(integ, x0, t, X, ns, ierr, errmsg=msg)
    call check_int(ierr, CUP_OK, 'run: ' // trim(msg))
    xf = X(:, ns)
    call check(cup_netlist_configurations_formed(nl) == 2_c_long, 'two configurations formed')
    call cup_integrator_free(integ)
    call cup_scene_free(s)
  end subroutine run_buck
end program test_f_switch
