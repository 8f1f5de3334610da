! test_f_scene -- the scene bindings (built only when libcatchup contains the
! scene loader): a scene from text and from examples/paper-fig2.yaml, its
! borrowed LCS / input / options / x0 drive an integrator whose trajectory
! equals the one built by hand through the Fortran API; overrides; errors.
!
!   test_f_scene SOURCE_DIR
program test_f_scene
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  implicit none
  character(len=*), parameter :: nl = new_line('a')
  character(len=:), allocatable :: text
  character(len=1024) :: srcdir
  character(len=CUP_ERRMSG_LEN) :: msg
  type(cup_scene_t) :: s
  type(cup_lcs_t) :: L
  type(cup_input_t) :: u
  type(cup_integrator_options) :: o
  real(c_double), allocatable :: x0(:), t1(:), X1(:, :), t2(:), X2(:, :)
  integer :: ierr, n1, n2

  call get_command_argument(1, srcdir)
  text = 'name: inline-case1' // nl // &
    'circuit: {R1: 1, R2: 2, R3: 1, L2: 1, L3: 2, C4: 1}' // nl // &
    'input:' // nl // &
    '  - {type: sine, amplitude: 16, frequency: 3}' // nl // &
    '  - {type: constant, value: -0.5}' // nl // &
    'x0: [0, 0, 0]' // nl // 'T: 1' // nl // 'n: 100' // nl // &
    'eps: "n^-2.1"' // nl // 'eta: "n^-1.05"' // nl

  call section('scene from text, with an override')
  call cup_scene_load_string(s, text, 'inline.yaml', ierr, overrides=['n=1000'], errmsg=msg)
  call check_int(ierr, CUP_OK, 'load_string: ' // trim(msg))
  call check(cup_scene_name(s) == 'inline-case1', 'name: ' // cup_scene_name(s))
  call check(cup_scene_eps_spec(s) == 'n^-2.1' .and. cup_scene_eta_spec(s) == 'n^-1.05', 'schedule texts')
  call check_contains(cup_scene_text(s), 'n: 1000', 'document after the override')
  call cup_scene_options(s, o, ierr)
  call check(ierr == CUP_OK .and. o%n == 1000 .and. o%T == 1, 'options: n overridden to 1000')
  call cup_scene_x0(s, x0, ierr)
  call check(ierr == CUP_OK .and. size(x0) == 3, 'x0')
  L = cup_scene_lcs(s)
  u = cup_scene_input(s)
  call check(L%borrowed .and. u%borrowed .and. cup_lcs_dim(L) == 3 .and. cup_input_dim(u) == 1, 'borrowed LCS and input')
  call run(L, u, o, x0, t1, X1, n1)
  call by_hand(o, t2, X2, n2)
  call check(n1 == 1001 .and. n2 == 1001, '1001 samples each')
  if (n1 == n2) call check(maxval(abs(X1 - X2)) <= 1d-14, 'scene run = hand-built run')
  call cup_lcs_free(L)                         ! borrowed: forgets only
  call cup_input_free(u)
  call check_int(cup_lcs_dim(cup_scene_lcs(s)), 3, 'scene intact after freeing borrowed handles')
  call cup_scene_free(s)
  call cup_scene_free(s)
  call check(.not. c_associated(s%ptr), 'scene freed')

  call section('scene file examples/paper-fig2.yaml')
  call cup_scene_load(s, trim(srcdir) // '/examples/paper-fig2.yaml', ierr, errmsg=msg)
  call check_int(ierr, CUP_OK, 'load: ' // trim(msg))
  call cup_scene_options(s, o, ierr)
  call check(ierr == CUP_OK .and. o%n >= 1, 'options of the file')
  call check_int(cup_scene_file_count(s), 1, 'one file read')
  call check(cup_scene_file(s, 1) == trim(srcdir) // '/examples/paper-fig2.yaml', 'the file read: ' // cup_scene_file(s, 1))
  call check(len(cup_scene_file_sha256(s, 1)) == 64 .and. cup_scene_file(s, 2) == '', 'its SHA-256; nothing beyond')
  call check(cup_scene_state_name(s, 1) == 'q(C4)' .and. cup_scene_state_unit(s, 1) == 'C', &
    'state 1 is the charge q(C4), in C')
  call check(cup_scene_state_name(s, 3) == 'i(L2)' .and. cup_scene_state_unit(s, 3) == 'A', 'state 3 is i(L2), in A')
  call check(cup_scene_state_name(s, 4) == '' .and. cup_scene_state_unit(s, 4) == '', 'no state 4 of 3')
  call cup_scene_free(s)

  call section('a set: scene, examples/tractrix.yaml')
  call cup_scene_load(s, trim(srcdir) // '/examples/tractrix.yaml', ierr, errmsg=msg)
  call check_int(ierr, CUP_OK, 'load: ' // trim(msg))
  call check_int(cup_scene_dim(s), 2, 'dimension from the ball')
  L = cup_scene_lcs(s)
  call check(.not. c_associated(L%ptr), 'no LCS')
  block
    type(cup_process_desc) :: d
    type(cup_integrator_t) :: integ
    logical :: found
    real(c_double), allocatable :: ts(:), Xs(:, :)
    integer :: ns
    call cup_scene_process(s, d, found)
    call check(found .and. d%n == 2 .and. d%p == 1, 'its process: n = 2, one signal (the centre)')
    call cup_scene_x0(s, x0, ierr)
    call cup_scene_integrator(s, integ, ierr, errmsg=msg)
    call check_int(ierr, CUP_OK, 'integrator: ' // trim(msg))
    call cup_integrator_run_store(integ, x0, ts, Xs, ns, ierr)
    call check(ierr == CUP_OK .and. ns == 1001, 'run: 1001 samples')
    call check(abs(Xs(2, ns) - 1 / cosh(5d0)) < 1d-3 .and. abs(Xs(1, ns) - (5 - tanh(5d0))) < 1d-3, &
      'the tractrix at t = 5')
    call cup_integrator_free(integ)
    deallocate(ts, Xs)
  end block
  call cup_scene_free(s)

  call section('errors')
  call cup_scene_load_string(s, 'circuit: {R1: 1' // nl, 'broken.yaml', ierr, errmsg=msg)
  call check_int(ierr, CUP_ERR_PARSE, 'YAML syntax error')
  call check_contains(msg, 'broken.yaml', 'message names the file')
  call check(.not. c_associated(s%ptr), 'failed load: null handle')
  call cup_scene_load_string(s, text, 'inline.yaml', ierr, overrides=['circuit.L3=-1'], errmsg=msg)
  call check(ierr < 0, 'override L3 = -1 fails')
  call check_contains(msg, 'L3', 'message names L3')
  call cup_scene_free(s)
  call cup_scene_load(s, trim(srcdir) // '/no/such/scene.yaml', ierr, errmsg=msg)
  call check(ierr < 0 .and. len_trim(msg) > 0, 'missing file: ' // trim(msg))
  deallocate(text, x0, t1, X1, t2, X2)
  call finish()

contains

  subroutine run(L, u, o, x0, t, X, ns)
    type(cup_lcs_t), intent(in) :: L
    type(cup_input_t), intent(in) :: u
    type(cup_integrator_options), intent(in) :: o
    real(c_double), intent(in) :: x0(:)
    real(c_double), allocatable, intent(out) :: t(:), X(:, :)
    integer, intent(out) :: ns
    type(cup_integrator_t) :: integ
    integer :: ierr
    call cup_integrator_create(integ, L, ierr, u=u, opt=o)
    call check_int(ierr, CUP_OK, 'integrator from the scene')
    call cup_integrator_run_store(integ, x0, t, X, ns, ierr)
    call check_int(ierr, CUP_OK, 'run')
    call cup_integrator_free(integ)
  end subroutine run

  subroutine by_hand(o, t, X, ns)
    type(cup_integrator_options), intent(in) :: o
    real(c_double), allocatable, intent(out) :: t(:), X(:, :)
    integer, intent(out) :: ns
    type(cup_lcs_t) :: L
    type(cup_input_t) :: u
    integer :: ierr
    call cup_lcs_circuit(L, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr)
    call cup_input_create(u, 1, ierr)
    call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
    call cup_input_add_constant(u, 1, -0.5d0, ierr)
    call run(L, u, o, [0d0, 0d0, 0d0], t, X, ns)
    call cup_input_free(u)
    call cup_lcs_free(L)
  end subroutine by_hand
end program test_f_scene
