! test_f_netlist -- the netlist API from Fortran (module catchup):
!  * the half-wave rectifier's names, .tran and row kind;
!  * its theta run against an independent RK4 of its ODE
!    C v' = max(0, (V - v)/Rs) - v/RL (docs/netlist.md): v(60 ms) to 1e-3 V;
!  * signals against Kirchhoff's laws at a given (t, x, zeta), and zeta of
!    the last step equal to the diode current (V - v)/Rs of the final state;
!  * its periodic steady state (module catchup_pss): v(0) against RK4 run
!    over 10 periods (the orbit attracts within two: its multiplier is
!    1e-9), the residuals, the multiplier, the period's average within
!    its extremes; a PWL source's error;
!  * sets, errors with their messages (a bad value, an undefined subcircuit),
!    and the list of files read.
program test_f_netlist
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  implicit none
  real(c_double), parameter :: pi = 3.14159265358979323846264338327950288_c_double
  character(len=512) :: dir
  type(cup_netlist_t) :: nl
  integer :: ierr, k
  character(len=CUP_ERRMSG_LEN) :: msg

  call get_command_argument(1, dir)
  call section('netlist: names, .tran, rows')
  call cup_netlist_load(nl, trim(dir) // '/halfwave-rc.cir', ierr, errmsg=msg)
  call check_int(ierr, CUP_OK, 'load halfwave-rc.cir: ' // trim(msg))
  call check(cup_netlist_state_name(nl, 1) == 'v(C1)', 'state 1 is v(C1)')
  call check(index(cup_netlist_source(nl), 'C1 out 0 100u') > 0, 'the source text is the file')
  call check(cup_netlist_row_name(nl, 1) == 'D1', 'row 1 is D1')
  call check(cup_netlist_input_name(nl, 1) == 'V1', 'input 1 is V1')
  call check(.not. cup_netlist_row_fixed(nl, 1), 'D1 is free (zeta is its current)')
  call check(cup_lcs_has_D(cup_netlist_lcs(nl)), 'its LCS has D /= 0')
  block
    real(c_double) :: tstep, tstop
    call check(cup_netlist_tran(nl, tstep, tstop), '.tran given')
    call check_close(tstep, 20d-6, 1d-20, 'TSTEP (20u)')
    call check_close(tstop, 60d-3, 1d-17, 'TSTOP (60m)')
  end block

  call section('netlist: theta against RK4, zeta and signals')
  block
    type(cup_integrator_options) :: o
    type(cup_integrator_t) :: integ
    real(c_double), allocatable :: t(:), X(:, :), x0(:)
    real(c_double) :: zeta(1), sig(3), vref
    integer :: ns
    call cup_integrator_options_default(o)
    o%scheme = CUP_SCHEME_THETA
    o%T = 60d-3
    o%n = 3000
    o%eps = cup_schedule(0, 0)
    o%eta = cup_schedule(0, 0)
    o%output = CUP_OUTPUT_FINAL
    call cup_integrator_create(integ, cup_netlist_lcs(nl), ierr, u=cup_netlist_input(nl), opt=o)
    call check_int(ierr, CUP_OK, 'integrator (theta)')
    call cup_netlist_x0(nl, x0, ierr)
    call cup_integrator_run_store(integ, x0, t, X, ns, ierr)
    call check_int(ierr, CUP_OK, 'run')
    vref = rk4_rectifier(60d-3, 300000)
    call check_close(X(1, ns), vref, 1d-3, 'v(out) at 60 ms against RK4')
    call cup_integrator_zeta(integ, zeta, ierr)
    call check_close(zeta(1), max(0d0, (10 * sin(2 * pi * 50 * 60d-3) - X(1, ns)) / 1), 1d-9, &
                     'zeta of the last step: the diode current (V - v)/Rs')
    call cup_netlist_probe(nl, 'v(in)', ierr, index=k)
    call check_int(k, 1, 'first probe')
    call cup_netlist_probe(nl, 'I(D1)', ierr)
    call cup_netlist_probe(nl, 'v(a,out)', ierr, index=k)
    call check_int(k, 3, 'third probe')
    call check(cup_netlist_signal_name(nl, 2) == 'i(D1)', 'canonical name i(D1)')
    call check(cup_netlist_signal_unit(nl, 2) == 'A' .and. cup_netlist_signal_unit(nl, 1) == 'V', 'units A, V')
    call cup_netlist_probe(nl, 'v(nowhere)', ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'unknown node')
    call check_contains(msg, "no node named 'nowhere'", 'its message')
    call cup_netlist_signals(nl, 0.004d0, [3.5d0], sig, ierr, zeta=[2.25d0])
    call check_int(ierr, CUP_OK, 'signals')
    call check_close(sig(1), 10 * sin(2 * pi * 50 * 0.004d0), 1d-13, 'v(in) = V(t)')
    call check_close(sig(2), 2.25d0, 1d-15, 'i(D1) = zeta')
    call check_close(sig(3), 10 * sin(2 * pi * 50 * 0.004d0) - 2.25d0 - 3.5d0, 1d-13, 'v(a,out) = V - Rs i - v')
    call cup_integrator_free(integ)
  end block
  call cup_netlist_free(nl)
  call cup_netlist_free(nl)                   ! a second free is harmless

  call section('netlist: steady state')
  call cup_netlist_load(nl, trim(dir) // '/halfwave-rc.cir', ierr)
  block
    type(cup_pss_t) :: r
    type(cup_pss_options) :: po
    type(cup_pss_info) :: info
    type(cup_measure) :: me
    real(c_double), allocatable :: x0(:), res(:), t(:), X(:, :), J(:, :)
    complex(c_double), allocatable :: mu(:)
    real(c_double) :: per
    call cup_input_period(cup_netlist_input(nl), per, ierr)
    call check_int(ierr, CUP_OK, 'the input period')
    call check_close(per, 20d-3, 1d-17, 'the period: 50 Hz')
    call cup_pss_options_default(po)
    po%samples = 2001
    call cup_pss_solve(r, cup_netlist_lcs(nl), ierr, u=cup_netlist_input(nl), opt=po, errmsg=msg)
    call check_int(ierr, CUP_OK, 'steady state: ' // trim(msg))
    call cup_pss_get_info(r, info)
    call cup_pss_x0(r, x0, ierr)
    call check_close(x0(1), rk4_rectifier(200d-3, 1000000), 1d-3, 'v(0) against RK4 over 10 periods')
    call cup_pss_residuals(r, res, ierr)
    call check_int(size(res), info%iterations + 1, 'a residual per iterate')
    call check(res(size(res)) <= 1d-10 * (abs(x0(1)) + 1d-9), 'the last residual below the target')
    call cup_pss_multipliers(r, mu, ierr)
    call check(size(mu) == 1 .and. abs(mu(1)) < 1d-6, 'one multiplier, |mu| < 1e-6')
    call cup_pss_monodromy(r, J, ierr)
    call check_close(J(1, 1), real(mu(1), c_double), 1d-15, 'the monodromy is its multiplier (n = 1)')
    call cup_pss_trajectory(r, t, X, ierr)
    call check_int(ierr, CUP_OK, 'the trajectory')
    call check_close(X(1, size(t)), x0(1), 1d-9, 'the period closes')
    call cup_measure_period(X(1, :), 0, me, ierr)
    call check(me%min < me%avg .and. me%avg < me%max .and. me%max <= 10, 'average within the extremes')
    call cup_pss_free(r)
    call check(.not. cup_netlist_steady_state(nl, per), 'halfwave-rc.cir does not ask for its steady state')
    call cup_input_period_fits(cup_netlist_input(nl), 40d-3, ierr)
    call check_int(ierr, CUP_OK, '40 ms is two periods')
    call cup_input_period_fits(cup_netlist_input(nl), 30d-3, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, '30 ms is not a whole number of periods')
    block
      character(len=:), allocatable :: na, nb
      call cup_netlist_element_nodes(nl, 'rs', na, nb, ierr)
      call check(ierr == CUP_OK .and. na == 'in' .and. nb == 'a', 'Rs is from in to a')
    end block
  end block
  call cup_netlist_free(nl)
  block
    real(c_double) :: T
    call cup_netlist_load_string(nl, 'pwl' // new_line('a') // 'V1 a 0 PWL(0 0 1m 1)' // new_line('a') // &
                                 'R1 a b 1' // new_line('a') // 'C1 b 0 1u' // new_line('a'), 'p.cir', ierr)
    call cup_input_period(cup_netlist_input(nl), T, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'a PWL source has no period')
    call check_contains(msg, 'not periodic', 'its message')
    call cup_netlist_free(nl)
  end block
  block
    real(c_double) :: T, t0
    call cup_netlist_load_string(nl, 'gate' // new_line('a') // 'V1 a 0 PULSE(0 1 76u jump jump 49u 100u)' // &
                                 new_line('a') // 'R1 a b 1' // new_line('a') // 'C1 b 0 1u' // new_line('a'), &
                                 'g.cir', ierr)
    call check_int(ierr, CUP_OK, 'the gate netlist loads')
    call cup_input_steady_phase(cup_netlist_input(nl), 0d0, T, t0, ierr)
    call check_int(ierr, CUP_OK, 'a pulse running past its period has a steady phase')
    call check(abs(T - 100d-6) <= 1d-18 .and. abs(t0 - 25d-6) <= 1d-18, 'T = 100 us, t0 = 76 + 49 - 100 us')
    call cup_netlist_set_time_origin(nl, t0, ierr)
    call check_int(ierr, CUP_OK, 'the netlist read from t0')
    call cup_netlist_free(nl)
  end block

  call section('netlist: the ideal buck measured with its jumps')
  ! V1 PULSE through the ideal diode D1 (the switch and the freewheeling
  ! path), D = 0.3137 (the edge between samples): lossless, so the
  ! efficiency P(RL) / -P(V1) is 1, and avg v(sw) = D Vin (tests/test_pss.c)
  call cup_netlist_load_string(nl, 'buck' // new_line('a') // 'V1 a 0 PULSE(0 12 0 jump jump 3.137u 10u)' // &
                               new_line('a') // 'D1 a sw' // new_line('a') // 'L1 sw out 100u' // new_line('a') // &
                               'C1 out 0 10u' // new_line('a') // 'RL out 0 5' // new_line('a'), 'buck.cir', ierr)
  call check_int(ierr, CUP_OK, 'the buck netlist')
  block
    type(cup_pss_t) :: r
    type(cup_pss_options) :: po
    type(cup_pss_info) :: info
    type(cup_measure) :: msw, mpin, mpout, mold
    real(c_double), allocatable :: t(:), X(:, :), Z(:, :), jt(:), sig(:, :)
    real(c_double) :: out(5)
    integer :: k
    call cup_netlist_probe(nl, 'v(sw)', ierr)
    call cup_netlist_probe(nl, 'v(a)', ierr)
    call cup_netlist_probe(nl, 'i(V1)', ierr)
    call cup_netlist_probe(nl, 'v(out)', ierr)
    call cup_netlist_probe(nl, 'i(RL)', ierr)
    call cup_pss_options_default(po)
    po%samples = 2001
    call cup_pss_solve(r, cup_netlist_lcs(nl), ierr, u=cup_netlist_input(nl), opt=po, errmsg=msg)
    call check_int(ierr, CUP_OK, 'the buck''s steady state: ' // trim(msg))
    call cup_pss_get_info(r, info)
    call cup_pss_trajectory(r, t, X, ierr, zeta=Z)
    call cup_pss_jumps(r, jt, ierr)
    call check(ierr == CUP_OK .and. size(jt) == 2, 'two jump times: the PULSE''s edges')
    call check_close(jt(1), 0d0, 0d0, 'the rising edge at t0')
    call check_close(jt(2), 3.137d-6, 1d-20, 'the falling edge at D Ts')
    allocate(sig(size(t), 3))
    do k = 1, size(t)
      call cup_netlist_signals(nl, t(k), X(:, k), out, ierr, zeta=Z(:, k))
      sig(k, :) = [out(1), out(2) * out(3), out(4) * out(5)]
    end do
    call cup_measure_period_jumps(sig(:, 1), jt, info%t0, info%period, 0, msw, ierr)
    call check_int(ierr, CUP_OK, 'v(sw) measured')
    call check_close(msw%avg, 0.3137d0 * 12, 1d-8, 'avg v(sw) = D Vin')
    call cup_measure_period_jumps(sig(:, 2), jt, info%t0, info%period, 0, mpin, ierr)
    call cup_measure_period_jumps(sig(:, 3), jt, info%t0, info%period, 0, mpout, ierr)
    call check_close(mpout%avg / (-mpin%avg), 1d0, 1d-9, 'efficiency 1 (lossless)')
    call cup_measure_period(sig(:, 3), 0, mold, ierr)
    call cup_measure_period(sig(:, 2), 0, mpin, ierr)
    call check(abs(mold%avg / (-mpin%avg) - 1) > 1d-4, 'the samples alone: off by O(h)')
    call cup_measure_period_jumps(sig(:, 1), [jt(2), jt(1)], info%t0, info%period, 0, msw, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'jump times out of order')
    call check_contains(msg, 'must be sorted', 'its message')
    call cup_pss_free(r)
  end block
  call cup_netlist_free(nl)

  call section('netlist: sets and errors')
  call cup_netlist_load(nl, trim(dir) // '/halfwave-rc.cir', ierr, sets=['RL=-1'], errmsg=msg)
  call check_int(ierr, CUP_ERR_PARSE, 'a negative resistance set')
  call check_contains(msg, "set 'RL=-1': RL: bad value: resistance must be > 0", 'its message')
  call cup_netlist_load_string(nl, 'title' // new_line('a') // 'X1 a 0 amp' // new_line('a'), 'x.cir', ierr, &
                               errmsg=msg)
  call check_int(ierr, CUP_ERR_PARSE, 'an X element of no subcircuit')
  call check_contains(msg, "x.cir:2:8: X1: subcircuit 'amp' is not defined", 'its message')
  call cup_netlist_load(nl, trim(dir) // '/halfwave-rc.cir', ierr)
  call check_int(cup_netlist_file_count(nl), 1, 'files read')
  call check_contains(cup_netlist_file(nl, 1), 'halfwave-rc.cir', 'the netlist is file 1')
  call cup_netlist_free(nl)
  call finish()

contains

  !> C v' = max(0, (V - v)/Rs) - v/RL, V = 10 sin(100 pi t), by RK4.
  real(c_double) function rk4_rectifier(T, n) result(v)
    real(c_double), intent(in) :: T
    integer, intent(in) :: n
    real(c_double) :: h, s, k1, k2, k3, k4
    integer :: i
    h = T / n
    v = 0
    do i = 0, n - 1
      s = i * h
      k1 = f(s, v)
      k2 = f(s + h / 2, v + h / 2 * k1)
      k3 = f(s + h / 2, v + h / 2 * k2)
      k4 = f(s + h, v + h * k3)
      v = v + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    end do
  end function rk4_rectifier

  real(c_double) function f(t, v)
    real(c_double), intent(in) :: t, v
    f = (max(0d0, (10 * sin(2 * pi * 50 * t) - v) / 1) - v / 1000) / 100d-6
  end function f
end program test_f_netlist
