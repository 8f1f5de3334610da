! catchup_projector -- Fortran wrappers of polyset.h and projector.h: the set
! and its (eps, eta)-projection (conventions in catchup_base).
module catchup_projector
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char, c_ptr, c_null_ptr, &
    c_associated, c_loc
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use catchup_constants
  use catchup_types
  use catchup_c
  use catchup_base
  implicit none
  private

  public :: cup_polyset_create, cup_polyset_free, cup_polyset_dim, cup_polyset_rows, &
    cup_polyset_lipschitz, cup_polyset_norm, cup_polyset_contains, cup_polyset_interior_direction
  public :: cup_projector_options_default, cup_projector_create, cup_projector_free, &
    cup_projector_set_offset, cup_projector_set_tolerances, cup_projector_offer_feasible, &
    cup_projector_reset, cup_project, cup_projector_lambda, cup_projector_feasible, &
    cup_projector_farkas, cup_proj_method_name, cup_proj_method_parse

contains

  ! ---- polyset.h -----------------------------------------------------------------

  !> K = {x : C x + g >= 0} with metric P: identity (default), diag(Pdiag), or
  !> the sparse SPD Psparse (lower triangle only if lower_only). g defaults to 0.
  subroutine cup_polyset_create(K, C, ierr, g, Pdiag, Psparse, lower_only, errmsg)
    type(cup_polyset_t), intent(out) :: K
    type(cup_csc_matrix), intent(in), target :: C
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: g(:), Pdiag(:)
    type(cup_csc_matrix), intent(in), optional, target :: Psparse
    logical, intent(in), optional :: lower_only
    character(len=*), intent(out), optional :: errmsg
    type(cup_metric), target :: P
    real(c_double), allocatable, target :: gl(:), dl(:)   ! see contiguous_copy
    type(c_ptr) :: gp
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (.not. allocated(C%colptr)) then
      call cup_fail_(CUP_ERR_ARG, 'polyset: C is empty (build it with cup_csc_from_*)', ierr, errmsg)
      return
    end if
    gp = c_null_ptr
    if (present(g)) then
      if (size(g) /= C%nrow) then
        call cup_size_fail_('polyset: g', size(g), int(C%nrow), ierr, errmsg)
        return
      end if
      gl = g
      if (size(gl) > 0) gp = c_loc(gl)
    end if
    if (present(Pdiag) .and. present(Psparse)) then
      call cup_fail_(CUP_ERR_ARG, 'polyset: give Pdiag or Psparse, not both', ierr, errmsg)
      return
    end if
    if (present(Pdiag)) then
      if (size(Pdiag) /= C%ncol) then
        call cup_size_fail_('polyset: Pdiag', size(Pdiag), int(C%ncol), ierr, errmsg)
        return
      end if
      dl = Pdiag
      P%kind = CUP_METRIC_DIAGONAL
      if (size(dl) > 0) P%diag = c_loc(dl)
    else if (present(Psparse)) then
      P%kind = CUP_METRIC_SPARSE
      P%matrix = cup_csc_view(Psparse)
      if (present(lower_only)) P%lower_only = merge(1_c_int, 0_c_int, lower_only)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_polyset_create(K%ptr, cup_csc_view(C), gp, c_loc(P), cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_polyset_create

  !> Free K (a borrowed handle is only forgotten) and null the handle.
  subroutine cup_polyset_free(K)
    type(cup_polyset_t), intent(inout) :: K
    if (.not. K%borrowed) call c_cup_polyset_free(K%ptr)
    K%ptr = c_null_ptr
    K%borrowed = .false.
  end subroutine cup_polyset_free

  integer function cup_polyset_dim(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_dim = int(c_cup_polyset_dim(K%ptr))
  end function cup_polyset_dim

  integer function cup_polyset_rows(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_rows = int(c_cup_polyset_rows(K%ptr))
  end function cup_polyset_rows

  !> Guaranteed upper bound on lambda_max(C P^-1 C^T).
  real(c_double) function cup_polyset_lipschitz(K)
    type(cup_polyset_t), intent(in) :: K
    cup_polyset_lipschitz = c_cup_polyset_lipschitz(K%ptr)
  end function cup_polyset_lipschitz

  !> The P-norm of v (dim entries); NaN if v has the wrong size or K is null.
  real(c_double) function cup_polyset_norm(K, v)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(in) :: v(:)
    if (.not. c_associated(K%ptr)) then
      cup_polyset_norm = ieee_value(0.0_c_double, ieee_quiet_nan)
    else if (size(v) /= c_cup_polyset_dim(K%ptr)) then
      cup_polyset_norm = ieee_value(0.0_c_double, ieee_quiet_nan)
    else
      cup_polyset_norm = c_cup_polyset_norm(K%ptr, v)
    end if
  end function cup_polyset_norm

  !> .true. if x is certainly in {C x + g >= 0} (g: the default offset if
  !> absent); .false. otherwise, also for wrong sizes or a null K.
  logical function cup_polyset_contains(K, x, g)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(in), optional :: g(:)
    real(c_double), allocatable, target :: gl(:)
    type(c_ptr) :: gp
    cup_polyset_contains = .false.
    if (.not. c_associated(K%ptr)) return
    if (size(x) /= c_cup_polyset_dim(K%ptr)) return
    gp = c_null_ptr
    if (present(g)) then
      if (size(g) /= c_cup_polyset_rows(K%ptr)) return
      gl = g
      if (size(gl) > 0) gp = c_loc(gl)
    end if
    cup_polyset_contains = c_cup_polyset_contains(K%ptr, gp, x) /= 0
  end function cup_polyset_contains

  !> A direction d with C d > 0 found at creation (found = .false. if none).
  subroutine cup_polyset_interior_direction(K, d, found, ierr)
    type(cup_polyset_t), intent(in) :: K
    real(c_double), intent(inout) :: d(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (cup_null_fail_(K%ptr, 'polyset', ierr)) return
    call cup_copy_out_(c_cup_polyset_interior_direction(K%ptr), int(c_cup_polyset_dim(K%ptr)), d, found, ierr)
  end subroutine cup_polyset_interior_direction

  ! ---- projector.h -----------------------------------------------------------------

  !> The library's defaults (from the C function).
  subroutine cup_projector_options_default(opt)
    type(cup_projector_options), intent(out) :: opt
    call c_cup_projector_options_default(opt)
  end subroutine cup_projector_options_default

  !> A projector onto K (K must outlive it). opt defaults to the library's;
  !> feasible_point (dim entries, copied) overrides opt%feasible_point.
  subroutine cup_projector_create(p, K, ierr, opt, feasible_point, errmsg)
    type(cup_projector_t), intent(out) :: p
    type(cup_polyset_t), intent(in) :: K
    integer, intent(out) :: ierr
    type(cup_projector_options), intent(in), optional :: opt
    real(c_double), intent(in), optional :: feasible_point(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_projector_options) :: o
    real(c_double), allocatable, target :: fl(:)
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(K%ptr, 'projector: polyset', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call c_cup_projector_options_default(o)
    end if
    if (present(feasible_point)) then
      if (size(feasible_point) /= c_cup_polyset_dim(K%ptr)) then
        call cup_size_fail_('projector: feasible_point', size(feasible_point), &
          int(c_cup_polyset_dim(K%ptr)), ierr, errmsg)
        return
      end if
      fl = feasible_point
      if (size(fl) > 0) o%feasible_point = c_loc(fl)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_projector_create(p%ptr, K%ptr, o, cmsg)
    if (st == CUP_OK) then
      p%dim = int(c_cup_polyset_dim(K%ptr))
      p%m = int(c_cup_polyset_rows(K%ptr))
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_projector_create

  subroutine cup_projector_free(p)
    type(cup_projector_t), intent(inout) :: p
    call c_cup_projector_free(p%ptr)
    p%ptr = c_null_ptr
    p%dim = 0
    p%m = 0
  end subroutine cup_projector_free

  !> Replace the offset g (m entries) for the following projections.
  subroutine cup_projector_set_offset(p, g, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: g(:)
    integer, intent(out) :: ierr
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    if (size(g) /= p%m) then
      call cup_size_fail_('g', size(g), p%m, ierr)
      return
    end if
    ierr = int(c_cup_projector_set_offset(p%ptr, g))
  end subroutine cup_projector_set_offset

  subroutine cup_projector_set_tolerances(p, eps_abs, eps_rel, eta_abs, eta_rel, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: eps_abs, eps_rel, eta_abs, eta_rel
    integer, intent(out) :: ierr
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    ierr = int(c_cup_projector_set_tolerances(p%ptr, eps_abs, eps_rel, eta_abs, eta_rel))
  end subroutine cup_projector_set_tolerances

  !> Offer w (dim entries), believed to be in K at the current offset, as
  !> the anchor of the eta certificates: .true. if accepted, that is, found
  !> feasible with a rounding bound (a point outside, or not finite, is not).
  function cup_projector_offer_feasible(p, w, ierr) result(accepted)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: w(:)
    integer, intent(out) :: ierr
    logical :: accepted
    accepted = .false.
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    if (size(w) /= p%dim) then
      call cup_size_fail_('w', size(w), p%dim, ierr)
      return
    end if
    accepted = c_cup_projector_offer_feasible(p%ptr, w) == 1
  end function cup_projector_offer_feasible

  !> Forget the warm start.
  subroutine cup_projector_reset(p)
    type(cup_projector_t), intent(in) :: p
    if (c_associated(p%ptr)) call c_cup_projector_reset(p%ptr)
  end subroutine cup_projector_reset

  !> z = an (eps, eta)-approximate P-projection of x (dim entries each; z and
  !> x must be different arrays). ierr: CUP_OK, CUP_WARN_NOT_CERTIFIED,
  !> CUP_ERR_EMPTY_SET (see cup_projector_farkas), CUP_ERR_NONFINITE, ...
  subroutine cup_project(p, x, z, ierr, info)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(inout) :: z(:)
    integer, intent(out) :: ierr
    type(cup_proj_info), intent(out), optional :: info
    type(cup_proj_info) :: pi
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    if (size(x) /= p%dim) then
      call cup_size_fail_('x', size(x), p%dim, ierr)
      return
    end if
    if (size(z) /= p%dim) then
      call cup_size_fail_('z', size(z), p%dim, ierr)
      return
    end if
    ierr = int(c_cup_project(p%ptr, x, z, pi))
    if (present(info)) info = pi
  end subroutine cup_project

  !> Multipliers lambda (m entries) of the last projection.
  subroutine cup_projector_lambda(p, lambda, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: lambda(:)
    integer, intent(out) :: ierr
    logical :: found
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    call cup_copy_out_(c_cup_projector_lambda(p%ptr), p%m, lambda, found, ierr)
  end subroutine cup_projector_lambda

  !> The exactly feasible point v (dim entries) of the last projection, if any.
  subroutine cup_projector_feasible(p, v, found, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: v(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    call cup_copy_out_(c_cup_projector_feasible(p%ptr), p%dim, v, found, ierr)
  end subroutine cup_projector_feasible

  !> After CUP_ERR_EMPTY_SET: the Farkas certificate y >= 0 (m entries).
  subroutine cup_projector_farkas(p, y, found, ierr)
    type(cup_projector_t), intent(in) :: p
    real(c_double), intent(inout) :: y(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    found = .false.
    if (cup_null_fail_(p%ptr, 'projector', ierr)) return
    call cup_copy_out_(c_cup_projector_farkas(p%ptr), p%m, y, found, ierr)
  end subroutine cup_projector_farkas

  function cup_proj_method_name(method) result(s)
    integer, intent(in) :: method
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_proj_method_name(int(method, c_int)))
  end function cup_proj_method_name

  !> "auto", "pg", "fista", "activeset" -> CUP_PROJ_*; -1 if unknown.
  integer function cup_proj_method_parse(name)
    character(len=*), intent(in) :: name
    cup_proj_method_parse = int(c_cup_proj_method_parse(cup_f_c_string(name)))
  end function cup_proj_method_parse

end module catchup_projector
