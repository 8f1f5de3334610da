! test_f_api -- the Fortran binding against the C compiler and the C library:
! struct layouts (offsets from the C helper), status constants and names,
! strings, versions, CSC conversion, polyset / projector / input / LCS /
! schedule / integrator wrappers with closed-form answers, error codes and
! messages, and double frees.
module layout_check
  use, intrinsic :: iso_c_binding
  use catchup
  use cup_testing
  implicit none
  private
  public :: test_layouts

  interface
    function cupt_layout(name, out, cap) bind(C, name="cupt_layout") result(n)
      import :: c_char, c_long, c_int
      character(kind=c_char), intent(in) :: name(*)
      integer(c_long), intent(inout) :: out(*)
      integer(c_int), value :: cap
      integer(c_int) :: n
    end function cupt_layout
  end interface

contains

  integer(c_long) function off(base, member)
    type(c_ptr), intent(in) :: base, member
    off = int(transfer(member, 0_c_intptr_t) - transfer(base, 0_c_intptr_t), c_long)
  end function off

  !> sizeof and every member offset as the Fortran compiler lays the type out
  !> must equal the C compiler's (a missing or extra member fails too).
  subroutine compare(name, f)
    character(len=*), intent(in) :: name
    integer(c_long), intent(in) :: f(:)
    integer(c_long) :: c(64)
    integer :: n, i
    n = int(cupt_layout(name // c_null_char, c, int(size(c), c_int)))
    call check(n > 0, 'layout: C knows ' // name)
    call check_int(size(f), n, 'layout: member count of ' // name)
    do i = 1, min(n, size(f))
      call check(f(i) == c(i), 'layout: ' // name // ' entry ' // achar(48 + i / 10) // achar(48 + mod(i, 10)) &
        // merge(' (sizeof)       ', ' (member offset)', i == 1))
    end do
  end subroutine compare

  subroutine test_layouts()
    type(cup_csc), target :: a
    type(cup_metric), target :: m
    type(cup_projector_options), target :: po
    type(cup_proj_info), target :: pi
    type(cup_wave), target :: w
    type(cup_lcs_desc), target :: d
    type(cup_circuit), target :: ci
    type(cup_schedule), target :: s
    type(cup_integrator_options), target :: o
    type(cup_run_info), target :: r
    type(cup_set_desc), target :: sd
    type(cup_process_desc), target :: pd
    type(cup_crowd_desc), target :: cd
    type(cup_pss_options), target :: so
    type(cup_pss_info), target :: si
    type(cup_measure), target :: me
    type(c_ptr) :: b
    call section('struct layouts against the C compiler')
    b = c_loc(a)
    call compare('cup_csc', [int(c_sizeof(a), c_long), off(b, c_loc(a%nrow)), off(b, c_loc(a%ncol)), &
      off(b, c_loc(a%colptr)), off(b, c_loc(a%rowind)), off(b, c_loc(a%values))])
    b = c_loc(m)
    call compare('cup_metric', [int(c_sizeof(m), c_long), off(b, c_loc(m%kind)), off(b, c_loc(m%diag)), &
      off(b, c_loc(m%matrix)), off(b, c_loc(m%lower_only))])
    b = c_loc(po)
    call compare('cup_projector_options', [int(c_sizeof(po), c_long), off(b, c_loc(po%method)), &
      off(b, c_loc(po%eps_abs)), off(b, c_loc(po%eps_rel)), off(b, c_loc(po%eta_abs)), &
      off(b, c_loc(po%eta_rel)), off(b, c_loc(po%max_iter)), off(b, c_loc(po%warm_start)), &
      off(b, c_loc(po%return_feasible)), off(b, c_loc(po%lipschitz)), off(b, c_loc(po%feasible_point)), &
      off(b, c_loc(po%factor_updates))])
    b = c_loc(pi)
    call compare('cup_proj_info', [int(c_sizeof(pi), c_long), off(b, c_loc(pi%status)), &
      off(b, c_loc(pi%method)), off(b, c_loc(pi%iterations)), off(b, c_loc(pi%factorizations)), &
      off(b, c_loc(pi%skipped)), off(b, c_loc(pi%active)), off(b, c_loc(pi%scale)), &
      off(b, c_loc(pi%eps_target)), off(b, c_loc(pi%eta_target)), off(b, c_loc(pi%eps_cert)), &
      off(b, c_loc(pi%eta_cert)), off(b, c_loc(pi%violation)), off(b, c_loc(pi%dual_value)), &
      off(b, c_loc(pi%farkas_gap)), off(b, c_loc(pi%farkas_residual)), off(b, c_loc(pi%row_updates))])
    b = c_loc(w)
    call compare('cup_wave', [int(c_sizeof(w), c_long), off(b, c_loc(w%kind)), off(b, c_loc(w%value)), &
      off(b, c_loc(w%amplitude)), off(b, c_loc(w%frequency)), off(b, c_loc(w%phase)), &
      off(b, c_loc(w%npoints)), off(b, c_loc(w%t)), off(b, c_loc(w%v)), off(b, c_loc(w%delay)), &
      off(b, c_loc(w%damping)), off(b, c_loc(w%value2)), off(b, c_loc(w%rise)), off(b, c_loc(w%fall)), &
      off(b, c_loc(w%width)), off(b, c_loc(w%period))])
    b = c_loc(d)
    call compare('cup_lcs_desc', [int(c_sizeof(d), c_long), off(b, c_loc(d%n)), off(b, c_loc(d%m)), &
      off(b, c_loc(d%p)), off(b, c_loc(d%A)), off(b, c_loc(d%B)), off(b, c_loc(d%C)), &
      off(b, c_loc(d%E)), off(b, c_loc(d%F)), off(b, c_loc(d%G)), off(b, c_loc(d%metric)), &
      off(b, c_loc(d%pb_tol)), off(b, c_loc(d%D)), off(b, c_loc(d%row_names))])
    b = c_loc(ci)
    call compare('cup_circuit', [int(c_sizeof(ci), c_long), off(b, c_loc(ci%R1)), off(b, c_loc(ci%R2)), &
      off(b, c_loc(ci%R3)), off(b, c_loc(ci%L2)), off(b, c_loc(ci%L3)), off(b, c_loc(ci%C4)), &
      off(b, c_loc(ci%G))])
    b = c_loc(s)
    call compare('cup_schedule', [int(c_sizeof(s), c_long), off(b, c_loc(s%coef)), off(b, c_loc(s%power))])
    b = c_loc(o)
    call compare('cup_integrator_options', [int(c_sizeof(o), c_long), off(b, c_loc(o%scheme)), &
      off(b, c_loc(o%T)), off(b, c_loc(o%n)), off(b, c_loc(o%eps)), off(b, c_loc(o%eta)), &
      off(b, c_loc(o%proj)), off(b, c_loc(o%output)), off(b, c_loc(o%output_every)), &
      off(b, c_loc(o%output_samples)), off(b, c_loc(o%f)), off(b, c_loc(o%f_ctx)), &
      off(b, c_loc(o%f_order)), off(b, c_loc(o%max_wall_seconds)), off(b, c_loc(o%theta)), &
      off(b, c_loc(o%on_step)), &
      off(b, c_loc(o%step_ctx)), off(b, c_loc(o%interrupt)), off(b, c_loc(o%tol_abs)), &
      off(b, c_loc(o%tol_rel)), off(b, c_loc(o%max_event_rate)), off(b, c_loc(o%on_event)), &
      off(b, c_loc(o%event_ctx)), off(b, c_loc(o%estimate)), off(b, c_loc(o%hmax)), &
      off(b, c_loc(o%output_t0)), off(b, c_loc(o%output_tol))])
    b = c_loc(r)
    call compare('cup_run_info', [int(c_sizeof(r), c_long), off(b, c_loc(r%status)), off(b, c_loc(r%step)), &
      off(b, c_loc(r%t)), off(b, c_loc(r%projected)), off(b, c_loc(r%skipped)), &
      off(b, c_loc(r%not_certified)), off(b, c_loc(r%dual_iterations)), off(b, c_loc(r%factorizations)), &
      off(b, c_loc(r%max_eps_cert)), off(b, c_loc(r%max_eta_cert)), off(b, c_loc(r%eps_target)), &
      off(b, c_loc(r%eta_target)), off(b, c_loc(r%h_rho)), off(b, c_loc(r%samples)), &
      off(b, c_loc(r%message)), off(b, c_loc(r%set_rebuilds)), off(b, c_loc(r%max_rows)), &
      off(b, c_loc(r%err_est)), off(b, c_loc(r%events)), off(b, c_loc(r%rejected))])
    call check_int(size(r%message), CUP_RUN_MSG_LEN, 'cup_run_info%message has CUP_RUN_MSG_LEN chars')
    b = c_loc(sd)
    call compare('cup_set_desc', [int(c_sizeof(sd), c_long), off(b, c_loc(sd%kind)), off(b, c_loc(sd%n)), &
      off(b, c_loc(sd%p)), off(b, c_loc(sd%metric)), off(b, c_loc(sd%C)), off(b, c_loc(sd%F)), &
      off(b, c_loc(sd%G)), off(b, c_loc(sd%center)), off(b, c_loc(sd%Gc)), off(b, c_loc(sd%radius)), &
      off(b, c_loc(sd%gr)), off(b, c_loc(sd%Q)), off(b, c_loc(sd%oracle)), off(b, c_loc(sd%oracle_ctx)), &
      off(b, c_loc(sd%rows)), off(b, c_loc(sd%rows_ctx))])
    b = c_loc(pd)
    call compare('cup_process_desc', [int(c_sizeof(pd), c_long), off(b, c_loc(pd%n)), off(b, c_loc(pd%p)), &
      off(b, c_loc(pd%C)), off(b, c_loc(pd%u)), off(b, c_loc(pd%A)), off(b, c_loc(pd%E)), &
      off(b, c_loc(pd%f)), off(b, c_loc(pd%f_ctx)), off(b, c_loc(pd%f_integral)), &
      off(b, c_loc(pd%f_integral_ctx))])
    b = c_loc(cd)
    call compare('cup_crowd_desc', [int(c_sizeof(cd), c_long), off(b, c_loc(cd%agents)), off(b, c_loc(cd%q0)), &
      off(b, c_loc(cd%radius)), off(b, c_loc(cd%room_points)), off(b, c_loc(cd%room)), off(b, c_loc(cd%doors)), &
      off(b, c_loc(cd%door)), off(b, c_loc(cd%obstacles)), off(b, c_loc(cd%obstacle_points)), &
      off(b, c_loc(cd%obstacle)), off(b, c_loc(cd%walls)), off(b, c_loc(cd%wall)), off(b, c_loc(cd%speed)), &
      off(b, c_loc(cd%grid)), off(b, c_loc(cd%margin)), off(b, c_loc(cd%reach)), &
      off(b, c_loc(cd%clearance))])
    b = c_loc(so)
    call compare('cup_pss_options', [int(c_sizeof(so), c_long), off(b, c_loc(so%period)), &
      off(b, c_loc(so%max_iter)), off(b, c_loc(so%tol)), off(b, c_loc(so%tol_floor)), off(b, c_loc(so%map_tol)), &
      off(b, c_loc(so%fd_step)), off(b, c_loc(so%warmup_periods)), off(b, c_loc(so%samples)), &
      off(b, c_loc(so%jacobian))])
    b = c_loc(si)
    call compare('cup_pss_info', [int(c_sizeof(si), c_long), off(b, c_loc(si%status)), off(b, c_loc(si%n)), &
      off(b, c_loc(si%m)), off(b, c_loc(si%iterations)), off(b, c_loc(si%period)), off(b, c_loc(si%residual)), &
      off(b, c_loc(si%max_multiplier)), off(b, c_loc(si%period_runs)), off(b, c_loc(si%events)), &
      off(b, c_loc(si%samples)), off(b, c_loc(si%seconds)), off(b, c_loc(si%message)), off(b, c_loc(si%t0)), &
      off(b, c_loc(si%jumps))])
    b = c_loc(me)
    call compare('cup_measure', [int(c_sizeof(me), c_long), off(b, c_loc(me%avg)), off(b, c_loc(me%rms)), &
      off(b, c_loc(me%min)), off(b, c_loc(me%max)), off(b, c_loc(me%pp)), off(b, c_loc(me%thd))])
  end subroutine test_layouts
end module layout_check

program test_f_api
  use, intrinsic :: iso_c_binding
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use catchup
  use cup_testing
  use layout_check
  implicit none

  interface
    function cupt_status_merge(a, b) bind(C, name="cupt_status_merge") result(m)
      import :: c_int
      integer(c_int), value :: a, b
      integer(c_int) :: m
    end function cupt_status_merge
  end interface

  call test_layouts()
  call test_status()
  call test_versions()
  call test_csc()
  call test_polyset()
  call test_projector()
  call test_input()
  call test_lcs()
  call test_schedule_and_options()
  call finish()

contains

  ! ---- status ----------------------------------------------------------------------
  subroutine one_status(code, name)
    integer, intent(in) :: code
    character(len=*), intent(in) :: name
    call check(cup_status_name(code) == name, 'status constant ' // name // ' is C''s ' // cup_status_name(code))
  end subroutine one_status

  subroutine test_status()
    integer :: i, v, a, b
    logical :: listed
    call section('status codes')
    ! every named constant against the C table (written out, as in README)
    call one_status(CUP_OK, 'CUP_OK')
    call one_status(CUP_ERR_NOMEM, 'CUP_ERR_NOMEM')
    call one_status(CUP_ERR_ARG, 'CUP_ERR_ARG')
    call one_status(CUP_ERR_DIM, 'CUP_ERR_DIM')
    call one_status(CUP_ERR_NONFINITE, 'CUP_ERR_NONFINITE')
    call one_status(CUP_ERR_NOT_SPD, 'CUP_ERR_NOT_SPD')
    call one_status(CUP_ERR_EMPTY_SET, 'CUP_ERR_EMPTY_SET')
    call one_status(CUP_ERR_PB_CT, 'CUP_ERR_PB_CT')
    call one_status(CUP_ERR_CALLBACK, 'CUP_ERR_CALLBACK')
    call one_status(CUP_ERR_DIVERGED, 'CUP_ERR_DIVERGED')
    call one_status(CUP_ERR_IO, 'CUP_ERR_IO')
    call one_status(CUP_ERR_PARSE, 'CUP_ERR_PARSE')
    call one_status(CUP_ERR_LINALG, 'CUP_ERR_LINALG')
    call one_status(CUP_ERR_TIME_LIMIT, 'CUP_ERR_TIME_LIMIT')
    call one_status(CUP_ERR_INTERRUPTED, 'CUP_ERR_INTERRUPTED')
    call one_status(CUP_ERR_UNSUPPORTED, 'CUP_ERR_UNSUPPORTED')
    call one_status(CUP_WARN_NOT_CERTIFIED, 'CUP_WARN_NOT_CERTIFIED')
    call one_status(CUP_WARN_STIFF, 'CUP_WARN_STIFF')
    call one_status(CUP_WARN_QUADRATURE, 'CUP_WARN_QUADRATURE')
    ! the generated table, and no C code missing from it
    do i = 1, CUP_STATUS_COUNT
      call check(cup_status_name(CUP_STATUS_CODES(i)) == trim(CUP_STATUS_NAMES(i)), &
        'generated table: ' // trim(CUP_STATUS_NAMES(i)))
    end do
    do v = -200, 200
      listed = any(CUP_STATUS_CODES == v)
      call check(listed .eqv. (cup_status_name(v) /= 'CUP_UNKNOWN'), 'status code coverage')
    end do
    call check(cup_status_string(CUP_ERR_EMPTY_SET) == 'the set is empty (Farkas certificate in info)', &
      'status string of CUP_ERR_EMPTY_SET')
    call check(cup_status_string(-9999) == 'unknown status', 'unknown status string')
    ! the Fortran restatement of the static inline merge
    do a = -16, 4
      do b = -16, 4
        call check(cup_status_merge(a, b) == cupt_status_merge(a, b), 'cup_status_merge equals C''s inline')
      end do
    end do
  end subroutine test_status

  subroutine test_versions()
    character(len=:), allocatable :: deps
    call section('versions')
    call check(cup_version() == CUP_VERSION_STRING, 'library ' // cup_version() // ' = module ' // CUP_VERSION_STRING)
    call check(CUP_VERSION_NUMBER == 10000 * CUP_VERSION_MAJOR + 100 * CUP_VERSION_MINOR + CUP_VERSION_PATCH, &
      'CUP_VERSION_NUMBER')
    deps = cup_dependency_versions()
    call check(index(deps, 'catchup ' // CUP_VERSION_STRING // ';') == 1, 'dependency versions: ' // deps)
    call check_contains(deps, 'CHOLMOD', 'dependency versions name CHOLMOD')
    call check(cup_c_string(c_null_ptr) == '', 'null C string is empty')
  end subroutine test_versions

  ! ---- sparse ------------------------------------------------------------------------
  subroutine test_csc()
    ! [[1 0 2], [0 3 0]] in 1-based CSC
    integer(c_int) :: colptr(4) = [1, 2, 3, 4], rowind(3) = [1, 2, 1]
    real(c_double) :: values(3) = [1, 3, 2]
    type(cup_csc_matrix), target :: a, b
    type(cup_csc) :: v
    integer :: ierr
    character(len=200) :: msg
    call section('CSC conversion')
    call cup_csc_from_fortran(colptr, rowind, values, 2, 3, a, ierr)
    call check_int(ierr, CUP_OK, 'csc from 1-based')
    call check(all(a%colptr == [0, 1, 2, 3]) .and. all(a%rowind == [0, 1, 0]), '0-based copy')
    call check(all(colptr == [1, 2, 3, 4]) .and. all(rowind == [1, 2, 1]), 'caller arrays unchanged')
    call cup_csc_from_fortran(a%colptr, a%rowind, a%values, 2, 3, b, ierr, base=0)
    call check(ierr == CUP_OK .and. all(b%rowind == a%rowind) .and. all(b%values == values), 'base = 0')
    call cup_csc_from_dense(reshape([1d0, 0d0, 0d0, 3d0, 2d0, 0d0], [2, 3]), b, ierr)
    call check(all(b%colptr == a%colptr) .and. all(b%rowind == a%rowind) .and. all(b%values == a%values), &
      'dense -> CSC equals the sparse copy')
    v = cup_csc_view(b)
    call check(v%nrow == 2 .and. v%ncol == 3 .and. c_associated(v%colptr, c_loc(b%colptr)), 'view points into the copy')
    call cup_csc_free(b)
    v = cup_csc_view(b)
    call check(.not. c_associated(v%colptr) .and. v%ncol == 0, 'view of a freed matrix is absent')
    call cup_csc_free(b)
    call cup_csc_from_fortran([0, 1, 2, 3], rowind, values, 2, 3, b, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'colptr(1) /= base')
    call check_contains(msg, 'colptr(1)', 'message names colptr(1)')
    call cup_csc_from_fortran(colptr, [1, 3, 1], values, 2, 3, b, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'row index out of range')
    call check_contains(msg, 'rowind(2) = 3', 'message names the row index')
    call cup_csc_from_fortran(colptr(1:3), rowind, values, 2, 3, b, ierr)
    call check_int(ierr, CUP_ERR_DIM, 'short colptr')
    call cup_csc_from_fortran(colptr, rowind(1:2), values, 2, 3, b, ierr)
    call check_int(ierr, CUP_ERR_DIM, 'short rowind')
  end subroutine test_csc

  ! ---- polyset: the paper's set C = [[0,1,-1],[0,1,0]], P = diag(1, 2, 1) ---------------
  subroutine paper_set(K, ierr, g)
    type(cup_polyset_t), intent(out) :: K
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: g(:)
    type(cup_csc_matrix) :: C
    call cup_csc_from_dense(reshape([0d0, 0d0, 1d0, 1d0, -1d0, 0d0], [2, 3]), C, ierr)
    call cup_polyset_create(K, C, ierr, g=g, Pdiag=[1d0, 2d0, 1d0])
  end subroutine paper_set

  subroutine test_polyset()
    type(cup_polyset_t) :: K, K2
    type(cup_csc_matrix) :: C
    real(c_double) :: d(3), nan
    logical :: found
    integer :: ierr
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('polyset')
    call paper_set(K, ierr)
    call check_int(ierr, CUP_OK, 'paper set')
    call check_int(cup_polyset_dim(K), 3, 'dim')
    call check_int(cup_polyset_rows(K), 2, 'rows')
    ! C P^-1 C^T = [[1/2 + 1, 1/2], [1/2, 1/2]]: lambda_max = 1 + sqrt(2)/2
    call check(cup_polyset_lipschitz(K) >= 1 + sqrt(2d0) / 2 - 1d-12, 'Lipschitz bound >= lambda_max')
    call check_close(cup_polyset_norm(K, [1d0, 1d0, 1d0]), 2d0, 1d-15, 'P-norm of (1,1,1)')
    call check(ieee_is_nan(cup_polyset_norm(K, [1d0, 1d0])), 'norm of a wrong-size vector is NaN')
    call check(cup_polyset_contains(K, [0d0, 1d0, 0.5d0]), 'contains (0, 1, 0.5)')
    call check(.not. cup_polyset_contains(K, [0d0, -1d0, 0d0]), 'does not contain (0, -1, 0)')
    call check(cup_polyset_contains(K, [0d0, -1d0, -2d0], g=[0d0, 2d0]), 'contains with offset g')
    call cup_polyset_interior_direction(K, d, found, ierr)
    call check_int(ierr, CUP_OK, 'interior direction')
    if (found) call check(d(2) - d(3) > 0 .and. d(2) > 0, 'C d > 0')
    call cup_polyset_free(K)
    call check(.not. c_associated(K%ptr), 'free nulls the handle')
    call cup_polyset_free(K)                       ! harmless
    ! errors
    nan = ieee_value(nan, ieee_quiet_nan)
    call cup_csc_from_dense(reshape([0d0, 0d0, 1d0, nan, -1d0, 0d0], [2, 3]), C, ierr)
    call cup_polyset_create(K2, C, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_NONFINITE, 'polyset with a NaN')
    call check(len_trim(msg) > 0, 'NaN message: ' // trim(msg))
    call check(.not. c_associated(K2%ptr), 'failed create leaves a null handle')
    call paper_set(K2, ierr, g=[1d0, 2d0, 3d0])
    call check_int(ierr, CUP_ERR_DIM, 'g of the wrong size')
    call cup_csc_from_dense(reshape([0d0, 0d0, 1d0, 1d0, -1d0, 0d0], [2, 3]), C, ierr)
    call cup_polyset_create(K2, C, ierr, Pdiag=[1d0, -2d0, 1d0], errmsg=msg)
    call check(ierr == CUP_ERR_NOT_SPD .or. ierr == CUP_ERR_ARG, 'negative diagonal metric: ' // trim(msg))
    call cup_polyset_free(K2)
  end subroutine test_polyset

  ! ---- projector ---------------------------------------------------------------------
  subroutine test_projector()
    type(cup_polyset_t) :: K
    type(cup_projector_t) :: p
    type(cup_projector_options) :: opt
    type(cup_proj_info) :: info
    type(cup_csc_matrix) :: C
    real(c_double) :: z(3), lambda(2), y(2), v(3)
    logical :: found
    integer :: ierr
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('projector')
    call cup_projector_options_default(opt)
    call check(opt%method == CUP_PROJ_AUTO .and. opt%max_iter == 100000 .and. opt%warm_start == 1, &
      'options from cup_projector_options_default')
    call check(.not. c_associated(opt%feasible_point), 'default feasible_point is null')
    call paper_set(K, ierr)
    opt%method = CUP_PROJ_ACTIVESET
    call cup_projector_create(p, K, ierr, opt=opt, errmsg=msg)
    call check_int(ierr, CUP_OK, 'projector create')
    call check(p%dim == 3 .and. p%m == 2, 'cached sizes')
    ! x = (0, -1, 0): only row 2 (x2 >= 0) is violated; in the P-metric the
    ! projection moves x2 alone: z = (0, 0, 0)? Row 1 then reads 0 - 0 >= 0. Yes.
    call cup_project(p, [0d0, -1d0, 0d0], z, ierr, info)
    call check_int(ierr, CUP_OK, 'project')
    ! the exact dense path aims active rows at a slack above their rounding
    ! bound (certainly feasible, eta_cert = 0): z2 lands a few ulps above 0
    call check(maxval(abs(z - [0d0, 0d0, 0d0])) <= 1d-13 .and. z(2) >= 0, 'projection of (0,-1,0)')
    call check(info%eta_cert == 0, 'the projection is certainly feasible')
    call check(info%skipped == 0 .and. info%status == CUP_OK, 'info filled')
    call cup_projector_lambda(p, lambda, ierr)
    ! KKT: P (z - x) = C^T lambda -> (0, 2, 0) = lambda_1 (0,1,-1) + lambda_2 (0,1,0)
    call check(ierr == CUP_OK .and. maxval(abs(lambda - [0d0, 2d0])) <= 1d-12, 'multipliers (0, 2)')
    call cup_project(p, [5d0, 2d0, 1d0], z, ierr, info)
    call check(ierr == CUP_OK .and. info%skipped == 1 .and. all(z == [5d0, 2d0, 1d0]), 'inside: skipped, z = x')
    call cup_project(p, [0d0, 1d0], z, ierr)
    call check_int(ierr, CUP_ERR_DIM, 'x of the wrong size')
    call cup_project(p, [0d0, ieee_value(0d0, ieee_quiet_nan), 0d0], z, ierr)
    call check_int(ierr, CUP_ERR_NONFINITE, 'NaN in x')
    call cup_projector_feasible(p, v, found, ierr)
    call check_int(ierr, CUP_OK, 'feasible point query')
    call cup_projector_set_tolerances(p, 0d0, 1d-12, 0d0, 1d-10, ierr)
    call check_int(ierr, CUP_OK, 'set tolerances')
    ! a moved offset: K = {x2 - x3 >= 1, x2 >= 0}
    call cup_projector_set_offset(p, [-1d0, 0d0], ierr)
    call check_int(ierr, CUP_OK, 'set offset')
    call cup_project(p, [0d0, 0d0, 0d0], z, ierr)
    call check(ierr == CUP_OK .and. z(2) - z(3) >= 1 - 1d-12, 'projection onto the moved set')
    call cup_projector_set_offset(p, [1d0], ierr)
    call check_int(ierr, CUP_ERR_DIM, 'offset of the wrong size')
    ! (0, 2, 0) is in the moved set (2 - 0 >= 1, 2 >= 0), (0, 0.5, 0) is not (0.5 - 0 < 1)
    call check(cup_projector_offer_feasible(p, [0d0, 2d0, 0d0], ierr) .and. ierr == CUP_OK, &
      'a point of the moved set is accepted as the anchor')
    call check(.not. cup_projector_offer_feasible(p, [0d0, 0.5d0, 0d0], ierr) .and. ierr == CUP_OK, &
      'a point outside is refused')
    call check(.not. cup_projector_offer_feasible(p, [0d0, 2d0], ierr) .and. ierr == CUP_ERR_DIM, &
      'an anchor of the wrong size')
    call cup_projector_reset(p)
    call cup_projector_free(p)
    call cup_projector_free(p)
    call check(.not. c_associated(p%ptr) .and. p%dim == 0, 'projector freed')
    call cup_project(p, [0d0, 0d0, 0d0], z, ierr)
    call check_int(ierr, CUP_ERR_ARG, 'project with a freed projector')
    call cup_polyset_free(K)
    ! empty set: x1 >= 1 and -x1 >= 0
    call cup_csc_from_dense(reshape([1d0, -1d0], [2, 1]), C, ierr)
    call cup_polyset_create(K, C, ierr, g=[-1d0, 0d0])
    call check_int(ierr, CUP_OK, 'empty set created')
    call cup_projector_create(p, K, ierr)
    if (ierr == CUP_OK) then
      call cup_project(p, [0.5d0], z(1:1), ierr, info)
      call check_int(ierr, CUP_ERR_EMPTY_SET, 'projection onto an empty set')
      call cup_projector_farkas(p, y, found, ierr)
      call check(found .and. ierr == CUP_OK, 'Farkas certificate available')
      ! y >= 0, C^T y ~ 0, g^T y < 0
      if (found) call check(all(y >= 0) .and. abs(y(1) - y(2)) <= 1d-12 * maxval(y) .and. -y(1) < 0, &
        'Farkas certificate is one')
      call cup_projector_free(p)
    else
      call check_int(ierr, CUP_ERR_EMPTY_SET, 'projector create on an empty set')
    end if
    call cup_polyset_free(K)
    call check(cup_proj_method_name(CUP_PROJ_FISTA) == 'fista', 'method name')
    call check_int(cup_proj_method_parse('activeset'), CUP_PROJ_ACTIVESET, 'method parse')
    call check_int(cup_proj_method_parse('newton?'), -1, 'unknown method')
  end subroutine test_projector

  ! ---- input -------------------------------------------------------------------------
  subroutine test_input()
    type(cup_input_t) :: u
    real(c_double) :: out(2), pi
    integer :: ierr
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('input')
    pi = acos(-1d0)
    call cup_input_create(u, 2, ierr)
    call check_int(ierr, CUP_OK, 'input create')
    call check_int(cup_input_dim(u), 2, 'input dim')
    call check(cup_input_is_constant(u), 'zero input is constant')
    call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
    call cup_input_add_constant(u, 1, -0.5d0, ierr)
    call cup_input_add_pwl(u, 2, [0d0, 1d0], [0d0, 2d0], ierr)
    call check_int(ierr, CUP_OK, 'terms added')
    call check(.not. cup_input_is_constant(u), 'not constant')
    call cup_input_eval(u, 0.1d0, out, ierr)
    call check_close(out(1), 16 * sin(6 * pi * 0.1d0) - 0.5d0, 1d-13, 'u_1(0.1), component 1 is Fortran''s 1')
    call check_close(out(2), 0.2d0, 1d-15, 'u_2(0.1) (PWL)')
    call cup_input_integral(u, 0d0, 0.5d0, out, ierr)
    call check_close(out(1), 16 * (1 - cos(3 * pi)) / (6 * pi) - 0.25d0, 1d-13, 'integral of u_1 over [0, 0.5]')
    call check_close(out(2), 0.25d0, 1d-15, 'integral of u_2 over [0, 0.5]')
    call check_close(cup_input_next_break(u, 0.5d0), 1d0, 1d-15, 'next PWL break')
    call cup_input_add_square(u, 2, 1d0, 2d0, ierr, phase=0d0)
    call check_close(cup_input_next_break(u, 0.1d0), 0.25d0, 1d-15, 'next square-wave jump')
    call cup_input_eval(u, 0.1d0, out(1:1), ierr)
    call check_int(ierr, CUP_ERR_DIM, 'eval into a short array')
    call cup_input_add_pwl(u, 1, [0d0, 1d0], [0d0], ierr, msg)
    call check_int(ierr, CUP_ERR_DIM, 'PWL with t and v of different sizes')
    call cup_input_add_pwl(u, 1, [1d0, 0d0], [0d0, 1d0], ierr, msg)
    call check(ierr < 0 .and. len_trim(msg) > 0, 'PWL times not increasing: ' // trim(msg))
    call cup_input_add_constant(u, 3, 1d0, ierr, msg)
    call check(ierr < 0, 'component 3 of 2: ' // trim(msg))
    call cup_input_set_callback(u, c_null_funptr, c_null_ptr, 1d-10, 0d0, ierr)
    call check_int(ierr, CUP_ERR_ARG, 'null callback')
    call cup_input_free(u)
    call cup_input_free(u)
    call check(.not. c_associated(u%ptr), 'input freed')
  end subroutine test_input

  ! ---- LCS ---------------------------------------------------------------------------
  subroutine test_lcs()
    type(cup_lcs_t) :: L, L2
    type(cup_polyset_t) :: K
    type(cup_circuit) :: c
    real(c_double) :: A(3, 3), B(3, 2), Cm(2, 3), E(3, 1), noG(2, 0), noF(0)
    integer :: ierr
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('LCS')
    c = cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0])
    call cup_lcs_circuit(L, c, ierr, msg)
    call check_int(ierr, CUP_OK, 'paper circuit')
    call check(cup_lcs_dim(L) == 3 .and. cup_lcs_rows(L) == 2 .and. cup_lcs_inputs(L) == 1, 'circuit sizes')
    call check(cup_lcs_fixed_set(L), 'G = 0: fixed set')
    K = cup_lcs_polyset(L)
    call check(K%borrowed .and. cup_polyset_dim(K) == 3, 'borrowed polyset')
    call check_close(cup_polyset_norm(K, [0d0, 1d0, 1d0]), sqrt(3d0), 1d-15, 'P = diag(1, L3, L2)')
    call cup_polyset_free(K)                        ! only forgets the pointer
    call check_int(cup_lcs_rows(L), 2, 'LCS intact after freeing the borrowed polyset')
    c%L3 = -1
    call cup_lcs_circuit(L2, c, ierr, msg)
    call check_int(ierr, CUP_ERR_ARG, 'L3 < 0')
    call check_contains(msg, 'L3', 'errmsg names L3')
    call check(.not. c_associated(L2%ptr), 'failed circuit: null handle')
    ! the same circuit from dense matrices (paper, Sec. 7)
    A = reshape([0d0, -0.5d0, 0d0, 1d0, -1d0, 1d0, 0d0, 0.5d0, -3d0], [3, 3])
    B = reshape([0d0, 0.5d0, -1d0, 0d0, 0.5d0, 0d0], [3, 2])
    Cm = reshape([0d0, 0d0, 1d0, 1d0, -1d0, 0d0], [2, 3])
    E = reshape([0d0, 0.5d0, 1d0], [3, 1])
    call cup_lcs_create_dense(A, B, Cm, E, noF, noG, [1d0, 2d0, 1d0], L2, ierr, errmsg=msg)
    call check_int(ierr, CUP_OK, 'dense paper circuit: ' // trim(msg))
    call check(cup_lcs_dim(L2) == 3 .and. cup_lcs_rows(L2) == 2 .and. cup_lcs_inputs(L2) == 1, 'dense sizes')
    call check(same_trajectory(L, L2), 'dense and built-in circuits give the same trajectory')
    call cup_lcs_free(L2)
    B(2, 1) = 0.25d0
    call cup_lcs_create_dense(A, B, Cm, E, noF, noG, [1d0, 2d0, 1d0], L2, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_PB_CT, 'P B /= C^T')
    call check(len_trim(msg) > 0, 'PB message: ' // trim(msg))
    call cup_lcs_create_dense(A(1:2, :), B, Cm, E, noF, noG, [1d0, 2d0, 1d0], L2, ierr, errmsg=msg)
    call check_int(ierr, CUP_ERR_DIM, 'A of the wrong shape')
    call check_contains(msg, 'A is 2 x 3', 'message gives the shape')
    call cup_lcs_free(L2)
    call cup_lcs_free(L)
    call cup_lcs_free(L)
  end subroutine test_lcs

  logical function same_trajectory(L1, L2)
    type(cup_lcs_t), intent(in) :: L1, L2
    type(cup_input_t) :: u
    type(cup_integrator_t) :: i1, i2
    type(cup_integrator_options) :: o
    real(c_double), allocatable :: t1(:), X1(:, :), t2(:), X2(:, :)
    integer :: n1, n2, ierr
    call cup_input_create(u, 1, ierr)
    call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
    call cup_input_add_constant(u, 1, -0.5d0, ierr)
    call cup_integrator_options_default(o)
    o%n = 200
    call cup_integrator_create(i1, L1, ierr, u=u, opt=o)
    call cup_integrator_create(i2, L2, ierr, u=u, opt=o)
    call cup_integrator_run_store(i1, [0d0, 0d0, 0d0], t1, X1, n1, ierr)
    call cup_integrator_run_store(i2, [0d0, 0d0, 0d0], t2, X2, n2, ierr)
    same_trajectory = n1 == 201 .and. n2 == 201
    if (same_trajectory) same_trajectory = maxval(abs(X1 - X2)) <= 1d-14 .and. all(t1 == t2)
    call cup_integrator_free(i1)
    call cup_integrator_free(i2)
    call cup_input_free(u)
  end function same_trajectory

  ! ---- schedules, options, integrator errors ---------------------------------------------
  subroutine test_schedule_and_options()
    type(cup_schedule) :: s
    type(cup_integrator_options) :: o
    type(cup_lcs_t) :: L
    type(cup_input_t) :: u
    type(cup_integrator_t) :: integ
    type(cup_run_info) :: info
    real(c_double) :: xfinal(3)
    real(c_double), allocatable :: t(:), X(:, :)
    integer :: ierr, ns
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('schedules and integrator options')
    call cup_schedule_parse('n^-2.1', s, ierr)
    call check(ierr == CUP_OK .and. s%coef == 1 .and. s%power == -2.1d0, 'parse n^-2.1')
    call check_close(cup_schedule_value(s, 1000), 1000d0**(-2.1d0), 1d-30, 'value at n = 1000')
    call check_close(cup_schedule_value(s, 1000_c_long), 1000d0**(-2.1d0), 1d-30, 'value at a c_long n')
    call check(round_trip(s), 'format and parse back: ' // cup_schedule_format(s))
    call check(index(cup_schedule_format(s), 'n^-2.1') == 1, 'format: ' // cup_schedule_format(s))
    call cup_schedule_parse('0.5*n^-1.05', s, ierr)
    call check(round_trip(s), 'format and parse back: ' // cup_schedule_format(s))
    call cup_schedule_parse('1e-06', s, ierr)
    call check(round_trip(s) .and. s%power == 0, 'constant schedule: ' // cup_schedule_format(s))
    call cup_schedule_parse('n^^2', s, ierr, msg)
    call check_int(ierr, CUP_ERR_PARSE, 'bad schedule')
    call check(len_trim(msg) > 0, 'parse message: ' // trim(msg))
    call cup_integrator_options_default(o)
    call check(o%n == 100 .and. o%T == 1 .and. o%f_order == 3 .and. o%output == CUP_OUTPUT_EVERY &
      .and. o%output_every == 1, 'integrator defaults from C')
    call check(o%eps%coef == 1 .and. o%eps%power == -2.1d0 .and. o%eta%power == -1.05d0, 'default schedules')
    call check(o%proj%max_iter == 100000, 'nested projector defaults')
    call check(.not. c_associated(o%f) .and. .not. c_associated(o%on_step), 'no callbacks by default')
    call check(cup_scheme_name(CUP_SCHEME_EXPONENTIAL) == 'exponential', 'scheme name')
    call check_int(cup_scheme_parse('implicit'), CUP_SCHEME_IMPLICIT, 'scheme parse')
    call check(CUP_SCHEME_COUNT == 5 .and. cup_scheme_name(CUP_SCHEME_THETA) == 'theta', 'theta in the list')
    call check(cup_scheme_name(CUP_SCHEME_ADAPTIVE) == 'adaptive' .and. o%tol_abs == 1d-6 .and. &
      o%tol_rel == 1d-6 .and. o%estimate == 0, 'adaptive scheme and its defaults')
    call check_int(cup_scheme_parse('theta'), 3, 'theta parse')
    call check(cup_scheme_name(CUP_SCHEME_COUNT) == 'unknown', 'past the list')
    call check_int(cup_output_parse('samples'), CUP_OUTPUT_SAMPLES, 'output parse')
    call check(cup_output_name(CUP_OUTPUT_NONE) == 'none' .and. CUP_OUTPUT_COUNT == 5, 'output name')
    call check(cup_output_name(CUP_OUTPUT_TOL) == 'tol' .and. cup_output_parse('tol') == CUP_OUTPUT_TOL, 'output tol')
    call check_int(cup_wave_parse('pwl'), CUP_WAVE_PWL, 'wave parse')
    call check(cup_wave_name(CUP_WAVE_SQUARE) == 'square' .and. cup_wave_parse('saw') == -1, 'wave name')
    call check_int(cup_proj_method_parse('fista'), CUP_PROJ_FISTA, 'method parse')
    call check(CUP_PROJ_METHOD_COUNT == 4, 'method count')
    call cup_lcs_circuit(L, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr)
    o%n = 0
    call cup_integrator_create(integ, L, ierr, opt=o, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'n = 0')
    call check_contains(msg, 'n = 0', 'message names n')
    o%n = 10
    o%output = CUP_OUTPUT_SAMPLES
    o%output_samples = 4
    call cup_integrator_create(integ, L, ierr, opt=o, errmsg=msg)
    call check_int(ierr, CUP_ERR_ARG, 'the circuit has an input: u is required')
    call check_contains(msg, 'no input', 'message')
    call cup_input_create(u, 1, ierr)                        ! u = 0
    call cup_integrator_create(integ, L, ierr, u=u, opt=o)
    call check_int(ierr, CUP_OK, 'integrator with a zero input')
    call cup_integrator_run_store(integ, [1d0, 0d0], t, X, ns, ierr, info, msg)
    call check_int(ierr, CUP_ERR_DIM, 'x0 of the wrong size')
    call check_contains(msg, 'x0 has 2 entries', 'message')
    call cup_integrator_run_store(integ, [1d0, 0d0, 0d0], t, X, ns, ierr, info)
    call check(ierr == CUP_OK .and. ns == 4 .and. size(X, 1) == 3 .and. size(X, 2) == 4, 'SAMPLES: 4 samples')
    call check(ns == 4 .and. info%samples == 4, 'info%samples')
    if (ns == 4) call check(all(abs(t - [0d0, 1d0/3, 2d0/3, 1d0]) <= 1d-15), 'sample times j T/3 (between steps)')
    call cup_integrator_state(integ, xfinal, ierr)
    if (ns == 4) call check(ierr == CUP_OK .and. all(xfinal == X(:, 4)), 'final state = last sample')
    call cup_integrator_run_store(integ, [ieee_value(0d0, ieee_quiet_nan), 0d0, 0d0], t, X, ns, ierr, info, msg)
    call check_int(ierr, CUP_ERR_NONFINITE, 'NaN in x0')
    call check_contains(msg, 'x0[0]', 'run message from C')
    call check(cup_run_info_message(info) == trim(msg), 'cup_run_info_message')
    call cup_integrator_free(integ)
    call cup_integrator_free(integ)
    call cup_integrator_run_store(integ, [0d0, 0d0, 0d0], t, X, ns, ierr)
    call check(ierr == CUP_ERR_ARG .and. ns == 0 .and. size(t) == 0, 'run a freed integrator')
    call cup_lcs_free(L)
    call cup_input_free(u)
    call test_checkpoint()
  end subroutine test_schedule_and_options

  !> A run stopped by the interrupt flag at step 1024, saved, restored into a
  !> new integrator and resumed ends in the state of the run never stopped,
  !> bit for bit; a blob refused by an integrator of another n.
  subroutine test_checkpoint()
    type(cup_integrator_options) :: o
    type(cup_lcs_t) :: L
    type(cup_input_t) :: u
    type(cup_integrator_t) :: integ, again
    type(cup_run_info) :: info
    integer(c_int), target :: flag
    integer(c_int8_t), allocatable :: blob(:)
    real(c_double) :: whole(3), resumed(3)
    integer :: ierr
    character(len=CUP_ERRMSG_LEN) :: msg
    call section('checkpoints')
    call cup_lcs_circuit(L, cup_circuit(R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, G=[0, 0]), ierr)
    call cup_input_create(u, 1, ierr)
    call cup_input_add_sine(u, 1, 16d0, 3d0, ierr)
    call cup_integrator_options_default(o)
    o%n = 5000
    o%output = CUP_OUTPUT_FINAL
    flag = 0
    o%interrupt = c_loc(flag)
    call cup_integrator_create(integ, L, ierr, u=u, opt=o)
    call cup_integrator_run(integ, [0d0, 0d0, 0d0], c_null_funptr, c_null_ptr, ierr, info)
    call cup_integrator_state(integ, whole, ierr)
    call check(cup_integrator_checkpoint_size(integ) < 0, 'a run that ended has no checkpoint')
    flag = 1
    call cup_integrator_run(integ, [0d0, 0d0, 0d0], c_null_funptr, c_null_ptr, ierr, info)
    call check(ierr == CUP_ERR_INTERRUPTED .and. info%step == 1024, 'stopped at step 1024')
    call cup_integrator_checkpoint_save(integ, info, blob, ierr)
    call check(ierr == CUP_OK .and. size(blob) == cup_integrator_checkpoint_size(integ), 'saved')
    flag = 0
    call cup_integrator_create(again, L, ierr, u=u, opt=o)
    call cup_integrator_checkpoint_restore(again, blob, ierr, msg)
    call check_int(ierr, CUP_OK, 'restored: ' // trim(msg))
    call cup_integrator_resume(again, c_null_funptr, c_null_ptr, ierr, info)
    call cup_integrator_state(again, resumed, ierr)
    call check(info%step == 5000 .and. info%status == CUP_OK .and. all(resumed == whole), 'resumed bit for bit')
    call cup_integrator_free(again)
    o%n = 5001
    call cup_integrator_create(again, L, ierr, u=u, opt=o)
    call cup_integrator_checkpoint_restore(again, blob, ierr, msg)
    call check(ierr == CUP_ERR_ARG, 'another n refused')
    call check_contains(msg, 'n = 5000 there, 5001 here', 'its message')
    call cup_integrator_free(again)
    call cup_integrator_free(integ)
    call cup_lcs_free(L)
    call cup_input_free(u)
  end subroutine test_checkpoint

  logical function round_trip(s)
    type(cup_schedule), intent(in) :: s
    type(cup_schedule) :: back
    integer :: ierr
    call cup_schedule_parse(cup_schedule_format(s), back, ierr)
    round_trip = ierr == CUP_OK .and. back%coef == s%coef .and. back%power == s%power
  end function round_trip
end program test_f_api
