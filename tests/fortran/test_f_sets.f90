! test_f_sets -- the general sweeping process from Fortran (module catchup,
! catchup_sets), against the closed forms of docs/closed-forms.md:
!  * the tractrix: a disc of radius 1 dragged at speed 1 (ball with a moving
!    centre, cup_integrator_create_process): error*n at n = 1e3 within 5% of
!    the C test's 0.5174;
!  * an oracle written in Fortran (the same disc's projection) gives the
!    built-in ball's trajectory to 1e-14;
!  * a state-dependent half-line {y >= t + x/2} from a Fortran rows callback
!    (columns counted from 1): error*n = 2 at n = 1e3;
!  * cup_setproj on an ellipsoid and an empty intersection, with messages;
!  * the one way errors travel: cup_setproj_place/_solve's errmsg is C's
!    words byte for byte (the texts of tests/test_set.c's
!    test_setproj_errmsg_one_way), the same status and words as the older
!    forms (cup_setproj_move/_project, cup_setproj_message).
module sets_cb
  use, intrinsic :: iso_c_binding
  implicit none
  type :: disc_par
    real(c_double) :: r = 1, v = 1
    integer :: calls = 0
  end type disc_par
contains
  !> The disc of radius r at (v t, 0), a few ulps inside as the built-in ball.
  function disc_oracle(t, x, eps, eta, z, eps_cert, eta_cert, ctx) result(stat) bind(C)
    real(c_double), value :: t, eps, eta
    real(c_double), intent(in) :: x(*)
    real(c_double), intent(inout) :: z(*)
    real(c_double), intent(out) :: eps_cert, eta_cert
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(disc_par), pointer :: p
    real(c_double) :: c1, v1, v2, d, s
    call c_f_pointer(ctx, p)
    p%calls = p%calls + 1
    c1 = p%v * t
    v1 = x(1) - c1
    v2 = x(2)
    d = sqrt(v1 * v1 + v2 * v2)
    if (d <= p%r) then
      z(1) = x(1)
      z(2) = x(2)
    else
      s = p%r * (1 - 4 * (2 + 8) * epsilon(1d0)) / d
      z(1) = c1 + s * v1
      z(2) = s * v2
    end if
    eps_cert = 0
    eta_cert = 0
    stat = 0
    if (eps < 0 .or. eta < 0) stat = 1
  end function disc_oracle

  !> C(t, x) = {y : y >= t + x/2}: the row 1 * y(1) - (t + x(1)/2) >= 0.
  function halfline_rows(t, x, rows, ctx) result(stat) bind(C)
    use catchup, only: cup_rowbuf_add
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    type(c_ptr), value :: rows, ctx
    integer(c_int) :: stat
    integer :: ierr
    call cup_rowbuf_add(rows, [1], [1d0], -(t + 0.5d0 * x(1)), ierr)
    stat = int(ierr, c_int)
    if (c_associated(ctx)) stat = 1
  end function halfline_rows

  !> f(t, x) = -x^3 (x' = -x^3: x = 1/sqrt(1 + 2t) from x = 1).
  function cubic_f(t, x, f, ctx) result(stat) bind(C)
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    real(c_double), intent(inout) :: f(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    f(1) = -x(1)**3
    stat = 0
    if (t < 0 .or. c_associated(ctx)) stat = 1
  end function cubic_f
end module sets_cb

program test_f_sets
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use catchup
  use sets_cb
  use cup_testing
  implicit none
  type(cup_set_t) :: ball, orc, half, ell, both
  type(cup_input_t) :: u
  type(cup_integrator_t) :: integ
  type(cup_integrator_options) :: opt
  type(cup_setproj_t) :: sp
  type(cup_proj_info) :: pi
  type(cup_run_info) :: info
  type(disc_par), target :: dp
  real(c_double), allocatable :: t(:), X(:, :), Xo(:, :), to(:)
  real(c_double) :: err, z(2), Q(2, 2)
  character(len=CUP_ERRMSG_LEN) :: msg
  integer :: ierr, ns, k

  call section('the tractrix: a ball with a moving centre')
  call cup_input_create(u, 1, ierr)
  call cup_input_add_pwl(u, 1, [0d0, 3d0], [0d0, 3d0], ierr)        ! u(t) = t
  call cup_set_ball_create(ball, [0d0, 0d0], 1d0, ierr, Gc=reshape([1d0, 0d0], [2, 1]))
  call check_int(ierr, CUP_OK, 'ball created')
  call check_int(cup_set_kind_of(ball), CUP_SET_BALL, 'its kind')
  call check(cup_set_kind_name(CUP_SET_BALL) == 'ball', 'kind name')
  call cup_integrator_options_default(opt)
  opt%T = 3
  opt%n = 1000
  opt%eps = cup_schedule(0, 0)
  opt%eta = cup_schedule(0, 0)
  call cup_integrator_create_process(integ, ball, ierr, u=u, opt=opt, errmsg=msg)
  call check_int(ierr, CUP_OK, 'process created: ' // trim(msg))
  call cup_integrator_run_store(integ, [0d0, 1d0], t, X, ns, ierr)
  call check_int(ierr, CUP_OK, 'tractrix run')
  err = 0
  do k = 1, ns
    err = max(err, abs(X(1, k) - (t(k) - tanh(t(k)))), abs(X(2, k) - 1 / cosh(t(k))))
  end do
  call check_close(err * 1000, 0.5174d0, 0.026d0, 'error*n of the tractrix at n = 1000')
  call check(integ%rows == 0, 'a ball has no rows')
  call cup_integrator_zeta(integ, z(1:0), ierr)
  call check_int(ierr, CUP_ERR_UNSUPPORTED, 'so no zeta')
  call cup_integrator_free(integ)

  call section('zeta of a process on a polyset: the half-line x >= 0 with x'' = -1 from 1/2')
  block
    type(cup_set_t) :: line
    type(cup_input_t) :: down
    type(cup_integrator_options) :: o10
    real(c_double) :: zz(1)
    real(c_double), allocatable :: tl(:), Xl(:, :)
    integer :: nl
    call cup_set_polyset_create(line, reshape([1d0], [1, 1]), ierr)
    call check_int(ierr, CUP_OK, 'half-line created')
    call cup_input_create(down, 1, ierr)
    call cup_input_add_constant(down, 1, -1d0, ierr)
    call cup_integrator_options_default(o10)
    o10%n = 10
    call cup_integrator_create_process(integ, line, ierr, u=down, E=reshape([1d0], [1, 1]), opt=o10)
    call check_int(ierr, CUP_OK, 'process created')
    call check(integ%rows == 1, 'one row')
    call cup_integrator_run_store(integ, [0.5d0], tl, Xl, nl, ierr)
    call check_int(ierr, CUP_OK, 'half-line run')
    call cup_integrator_zeta(integ, zz, ierr)
    call check_int(ierr, CUP_OK, 'its zeta')
    call check_close(zz(1), 1d0, 1d-12, 'zeta = 1 holds x on the boundary (x'' = -1 + zeta = 0)')
    call check(abs(Xl(1, nl)) <= 1d-12 .and. tl(nl) == 1, 'x(1) = 0')
    call cup_integrator_free(integ)
    call cup_input_free(down)
    call cup_set_free(line)
  end block

  call section('a Fortran oracle gives the built-in ball''s trajectory')
  call cup_set_oracle_create(orc, 2, c_funloc(disc_oracle), c_loc(dp), ierr)
  call check_int(ierr, CUP_OK, 'oracle set created')
  call cup_integrator_create_process(integ, orc, ierr, opt=opt)
  call check_int(ierr, CUP_OK, 'oracle process created')
  call cup_integrator_run_store(integ, [0d0, 1d0], to, Xo, ns, ierr, info)
  call check_int(ierr, CUP_OK, 'oracle run')
  call check(maxval(abs(Xo - X)) <= 1d-14, 'same trajectory to rounding')
  call check(dp%calls == 2 * (opt%n + 1), 'two oracle calls a step (the answer, its check) and two for x0')
  call cup_integrator_free(integ)

  call section('a state-dependent half-line from a Fortran rows callback')
  call cup_set_state_polyset_create(half, 1, c_funloc(halfline_rows), c_null_ptr, ierr)
  call check_int(ierr, CUP_OK, 'state polyset created')
  opt%T = 1
  call cup_integrator_create_process(integ, half, ierr, opt=opt)
  call cup_integrator_run_store(integ, [0d0], t, X, ns, ierr, info)
  call check_int(ierr, CUP_OK, 'half-line run')
  call check_close(abs(X(1, ns) - 2) * 1000, 2d0, 1d-6, 'error*n = 2 at the end')
  call check(info%set_rebuilds == 1 .and. info%max_rows == 1, 'one analysis, one row')
  call cup_integrator_free(integ)

  call section('a nonlinear f from Fortran: x'' = -x^3 in a ball it never reaches')
  block
    type(cup_set_t) :: big
    type(c_funptr) :: fp
    real(c_double), allocatable :: tc(:), Xc(:, :)
    integer :: nc
    call cup_set_ball_create(big, [0d0], 10d0, ierr)
    opt%T = 2
    fp = c_funloc(cubic_f)          ! a variable: c_funloc in the call would be a constant in .rodata
    call cup_integrator_create_process(integ, big, ierr, f=fp, opt=opt, errmsg=msg)
    call check_int(ierr, CUP_OK, 'process with f: ' // trim(msg))
    call cup_integrator_run_store(integ, [1d0], tc, Xc, nc, ierr)
    call check_close(abs(Xc(1, nc) - 1 / sqrt(5d0)) * 1000, 0.0d0, 0.37d0, 'Euler''s error*n at t = 2')
    call cup_integrator_free(integ)
    call cup_set_free(big)
    deallocate(tc, Xc)
  end block

  call section('cup_setproj: an ellipsoid, an empty intersection')
  Q = reshape([4d0, 0d0, 0d0, 1d0], [2, 2])                       ! 4 x^2 + y^2 <= 1
  call cup_set_ellipsoid_create(ell, [0d0, 0d0], 1d0, Q, ierr)
  call cup_setproj_create(sp, ell, ierr)
  call cup_setproj_move(sp, 0d0, ierr)
  call cup_setproj_project(sp, [0d0, 3d0], z, ierr, pi)
  call check_int(ierr, CUP_OK, 'ellipsoid projection certified')
  call check_close(z(2), 1d0, 1d-13, 'projection of (0, 3) is (0, 1), a few ulps inside')
  call cup_setproj_free(sp)
  call cup_set_intersection_create(both, reshape([1d0, 0d0], [1, 2]), [0d0, 0d0], 1d0, ierr, F=[-2d0])
  call cup_setproj_create(sp, both, ierr)
  call cup_setproj_move(sp, 0d0, ierr)
  call cup_setproj_project(sp, [3d0, 3d0], z, ierr, errmsg=msg)
  call check_int(ierr, CUP_ERR_EMPTY_SET, '{x1 >= 2} and the unit ball do not meet')
  call check_contains(msg, 'do not meet', 'the message says so')
  call cup_setproj_free(sp)

  call section('one way: cup_setproj_place/_solve, errmsg byte for byte, the older forms agree')
  block
    type(cup_set_t) :: shrink
    real(c_double) :: xs(2)
    real(c_double), target :: u_empty(1) = [1.25d0]
    integer :: iold
    character(len=CUP_ERRMSG_LEN) :: old
    ! r(t) = 1 - u: u = 0.5 gives radius 0.5, u = 1.25 radius -0.25 (empty)
    call cup_set_ball_create(shrink, [0d0, 0d0], 1d0, ierr, gr=[-1d0])
    call cup_setproj_create(sp, shrink, ierr)
    msg = 'untouched'
    call cup_setproj_place(sp, 0.5d0, ierr, u=[0.5d0], errmsg=msg)
    call check_int(ierr, CUP_OK, 'placed at u = 0.5')
    call check_words(msg, '', 'no words on success')
    call cup_setproj_solve(sp, [3d0, 4d0], z, ierr, pi, errmsg=msg)
    call check_int(ierr, CUP_OK, '(3, 4) projected onto radius 0.5')
    call check_close(z(1), 0.3d0, 1d-14, 'z(1) = 0.3, a few ulps inside')
    call check_close(z(2), 0.4d0, 1d-14, 'z(2) = 0.4')
    call check_words(msg, '', 'no words on success')
    call cup_setproj_place(sp, 1.25d0, ierr, u=[1.25d0], errmsg=msg)
    call check_int(ierr, CUP_ERR_EMPTY_SET, 'a negative radius: empty')
    call check_words(msg, 'the radius r(t) = -0.25 < 0: the ball is empty', 'place''s words')
    call check_words(cup_setproj_message(sp), trim(msg), 'the older cup_setproj_message, the same words')
    call cup_setproj_move(sp, 1.25d0, iold, u=[1.25d0], errmsg=old)
    call check_int(iold, ierr, 'cup_setproj_move: the same status')
    call check_words(old, trim(msg), 'cup_setproj_move: the same words')
    call check_int(int(c_cup_setproj_move(sp%ptr, 1.25d0, c_loc(u_empty), c_null_ptr)), ierr, &
                   'the C older form: the same status')
    call check_words(cup_setproj_message(sp), trim(msg), 'the C older form: the same words')
    call cup_setproj_place(sp, 1.25d0, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'no u for a moving set')
    call check_words(msg, 'the set moves with 1 parameters but u is NULL', 'place''s words')
    call cup_setproj_place(sp, 0.5d0, ierr, u=[0.5d0])
    xs = [3d0, ieee_value(0d0, ieee_quiet_nan)]
    z = -7
    call cup_setproj_solve(sp, xs, z, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_NONFINITE, 'a NaN in x')
    call check_words(msg, 'x[1] is nan', 'solve''s words (C counts from 0)')
    call check(all(z == -7), 'z unchanged on an error')
    call cup_setproj_project(sp, xs, z, iold, errmsg=old)
    call check_int(iold, ierr, 'cup_setproj_project: the same status')
    call check_words(old, trim(msg), 'cup_setproj_project: the same words')
    call check_words(cup_setproj_message(sp), trim(msg), 'cup_setproj_message: the same words')
    call cup_setproj_free(sp)
    call cup_setproj_solve(sp, xs, z, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'a freed handle')
    call check_words(msg, 'set projector handle is null', 'the wrapper''s words')
    call cup_set_free(shrink)
  end block

  call cup_set_free(both)
  call cup_set_free(ell)
  call cup_set_free(half)
  call cup_set_free(orc)
  call cup_set_free(ball)
  call cup_set_free(ball)          ! a second free is harmless
  call cup_input_free(u)
  deallocate(t, X, to, Xo)
  call finish()
end program test_f_sets
