! catchup_sets -- set.h in Fortran: the moving sets of a general sweeping
! process, their certified projections (cup_setproj_*) and the rows of a
! state-dependent polyset (cup_rowbuf_*): raw bind(C) interfaces c_cup_*,
! then wrappers (conventions in catchup_base). Dense matrices are accepted
! where C takes a CSC view; columns given to cup_rowbuf_add/expect are
! numbered from 1, as Fortran counts (the C side gets them from 0).
module catchup_sets
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_funptr, &
    c_null_ptr, c_null_char, c_loc, c_associated
  use catchup_constants
  use catchup_types
  use catchup_base
  use catchup_c, only: c_cup_projector_options_default
  implicit none
  private

  public :: c_cup_set_create, c_cup_set_free, c_cup_set_dim, c_cup_set_params, c_cup_set_kind_of, &
    c_cup_set_kind_name, c_cup_set_kind_parse, c_cup_setproj_create, c_cup_setproj_free, &
    c_cup_setproj_place, c_cup_setproj_solve, c_cup_setproj_move, c_cup_setproj_project, &
    c_cup_setproj_set_tolerances, c_cup_setproj_message, c_cup_setproj_rows, c_cup_setproj_rebuilds, &
    c_cup_rowbuf_add, c_cup_rowbuf_expect, c_cup_rowbuf_rows
  public :: cup_set_create, cup_set_ball_create, cup_set_ellipsoid_create, cup_set_halfspace_create, &
    cup_set_polyset_create, cup_set_intersection_create, cup_set_oracle_create, &
    cup_set_state_polyset_create, cup_set_free, cup_set_dim, cup_set_params, cup_set_kind_of, &
    cup_set_kind_name, cup_set_kind_parse
  public :: cup_setproj_create, cup_setproj_free, cup_setproj_place, cup_setproj_solve, &
    cup_setproj_move, cup_setproj_project, cup_setproj_set_tolerances, cup_setproj_message, &
    cup_setproj_rows, cup_setproj_rebuilds
  public :: cup_rowbuf_add, cup_rowbuf_expect, cup_rowbuf_rows

  ! The raw bind(C) interfaces c_<C name>, generated from the header at build time (gen_bindings.py)
  include "bind_set.inc"

  !> What a set description points into: kept alive by the wrapper until the
  !> C side has copied it.
  type :: desc_store
    type(cup_csc_matrix) :: C, G, Gc, Q
    real(c_double), allocatable :: F(:), center(:), gr(:), pdiag(:)
  end type desc_store

contains

  !> Any set from its C description (the views must point into live arrays).
  subroutine cup_set_create(S, d, ierr, errmsg)
    type(cup_set_t), intent(out) :: S
    type(cup_set_desc), intent(in) :: d
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_set_create(S%ptr, d, cmsg)
    if (st == CUP_OK) S%dim = int(d%n)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_set_create

  ! Fill the parts of d that the optional dense arguments give (copied into
  ! keep, which the caller holds until cup_set_create returns).
  subroutine describe(d, keep, n, ierr, C, F, G, center, Gc, radius, gr, Q, Pdiag)
    type(cup_set_desc), intent(inout) :: d
    type(desc_store), intent(inout), target :: keep
    integer, intent(in) :: n
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: C(:, :), F(:), G(:, :), center(:), Gc(:, :), gr(:), Q(:, :), Pdiag(:)
    real(c_double), intent(in), optional :: radius
    ierr = CUP_OK
    d%n = int(n, c_int)
    if (present(C)) then
      call cup_csc_from_dense(C, keep%C, ierr)
      d%C = cup_csc_view(keep%C)
    end if
    if (present(F)) then
      keep%F = F
      if (size(keep%F) > 0) d%F = c_loc(keep%F)
    end if
    if (present(G)) then
      call cup_csc_from_dense(G, keep%G, ierr)
      d%G = cup_csc_view(keep%G)
      d%p = int(size(G, 2), c_int)
    end if
    if (present(center)) then
      keep%center = center
      d%center = c_loc(keep%center)
    end if
    if (present(Gc)) then
      call cup_csc_from_dense(Gc, keep%Gc, ierr)
      d%Gc = cup_csc_view(keep%Gc)
      d%p = int(size(Gc, 2), c_int)
    end if
    if (present(radius)) d%radius = radius
    if (present(gr)) then
      keep%gr = gr
      d%gr = c_loc(keep%gr)
      d%p = int(size(gr), c_int)
    end if
    if (present(Q)) then
      call cup_csc_from_dense(Q, keep%Q, ierr)
      d%Q = cup_csc_view(keep%Q)
    end if
    if (present(Pdiag)) then
      keep%pdiag = Pdiag
      d%metric%kind = CUP_METRIC_DIAGONAL
      d%metric%diag = c_loc(keep%pdiag)
    end if
  end subroutine describe

  !> The ball {||x - c||_P <= r}, c = center + Gc u, r = radius + gr . u
  !> (P = diag(Pdiag), or the identity).
  subroutine cup_set_ball_create(S, center, radius, ierr, Gc, gr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    real(c_double), intent(in) :: center(:), radius
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: Gc(:, :), gr(:), Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = CUP_SET_BALL
    call describe(d, keep, size(center), ierr, center=center, radius=radius, Gc=Gc, gr=gr, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine cup_set_ball_create

  !> The ellipsoid {(x - c)^T Q (x - c) <= r^2}, projected in the P-metric.
  subroutine cup_set_ellipsoid_create(S, center, radius, Q, ierr, Gc, gr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    real(c_double), intent(in) :: center(:), radius, Q(:, :)
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: Gc(:, :), gr(:), Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = CUP_SET_ELLIPSOID
    call describe(d, keep, size(center), ierr, center=center, radius=radius, Q=Q, Gc=Gc, gr=gr, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine cup_set_ellipsoid_create

  !> The half-space {a . x + b + G u >= 0} (G: 1 x p).
  subroutine cup_set_halfspace_create(S, a, b, ierr, G, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    real(c_double), intent(in) :: a(:), b
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: G(:, :), Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = CUP_SET_HALFSPACE
    call describe(d, keep, size(a), ierr, C=reshape(a, [1, size(a)]), F=[b], G=G, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine cup_set_halfspace_create

  !> The polyset {C x + F + G u >= 0} (C: m x n dense).
  subroutine cup_set_polyset_create(S, C, ierr, F, G, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    real(c_double), intent(in) :: C(:, :)
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: F(:), G(:, :), Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = CUP_SET_POLYSET
    call describe(d, keep, size(C, 2), ierr, C=C, F=F, G=G, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine cup_set_polyset_create

  !> A polyset and a ball: {C x + F + G u >= 0} and {||x - c||_P <= r}.
  subroutine cup_set_intersection_create(S, C, center, radius, ierr, F, G, Gc, gr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    real(c_double), intent(in) :: C(:, :), center(:), radius
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: F(:), G(:, :), Gc(:, :), gr(:), Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = CUP_SET_INTERSECTION
    call describe(d, keep, size(C, 2), ierr, C=C, F=F, G=G, center=center, radius=radius, Gc=Gc, &
      gr=gr, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine cup_set_intersection_create

  !> A set given by the user's projection: oracle = c_funloc of a bind(C)
  !> procedure(cup_oracle_fn), ctx passed to it.
  subroutine cup_set_oracle_create(S, n, oracle, ctx, ierr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    integer, intent(in) :: n
    type(c_funptr), value :: oracle        ! VALUE: a c_funloc(...) actual needs no static temporary
    type(c_ptr), value :: ctx
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    call callback_set(S, CUP_SET_ORACLE, n, oracle, ctx, ierr, Pdiag, errmsg)
  end subroutine cup_set_oracle_create

  !> A state-dependent polyset: rows = c_funloc of a bind(C)
  !> procedure(cup_rows_fn), rebuilt from x_k at every step.
  subroutine cup_set_state_polyset_create(S, n, rows, ctx, ierr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    integer, intent(in) :: n
    type(c_funptr), value :: rows          ! VALUE, as the oracle
    type(c_ptr), value :: ctx
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    call callback_set(S, CUP_SET_STATE_POLYSET, n, rows, ctx, ierr, Pdiag, errmsg)
  end subroutine cup_set_state_polyset_create

  ! A set of a callback: the oracle's or the rows'.
  subroutine callback_set(S, kind, n, fn, ctx, ierr, Pdiag, errmsg)
    type(cup_set_t), intent(out) :: S
    integer(c_int), intent(in) :: kind
    integer, intent(in) :: n
    type(c_funptr), value :: fn
    type(c_ptr), value :: ctx
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: Pdiag(:)
    character(len=*), intent(out), optional :: errmsg
    type(cup_set_desc) :: d
    type(desc_store), target :: keep
    d%kind = kind
    if (kind == CUP_SET_ORACLE) then
      d%oracle = fn
      d%oracle_ctx = ctx
    else
      d%rows = fn
      d%rows_ctx = ctx
    end if
    call describe(d, keep, n, ierr, Pdiag=Pdiag)
    call cup_set_create(S, d, ierr, errmsg)
  end subroutine callback_set

  subroutine cup_set_free(S)
    type(cup_set_t), intent(inout) :: S
    call c_cup_set_free(S%ptr)
    S%ptr = c_null_ptr
    S%dim = 0
  end subroutine cup_set_free

  integer function cup_set_dim(S)
    type(cup_set_t), intent(in) :: S
    cup_set_dim = int(c_cup_set_dim(S%ptr))
  end function cup_set_dim

  integer function cup_set_params(S)
    type(cup_set_t), intent(in) :: S
    cup_set_params = int(c_cup_set_params(S%ptr))
  end function cup_set_params

  integer function cup_set_kind_of(S)
    type(cup_set_t), intent(in) :: S
    cup_set_kind_of = int(c_cup_set_kind_of(S%ptr))
  end function cup_set_kind_of

  function cup_set_kind_name(kind) result(s)
    integer, intent(in) :: kind
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_set_kind_name(int(kind, c_int)))
  end function cup_set_kind_name

  integer function cup_set_kind_parse(name)
    character(len=*), intent(in) :: name
    cup_set_kind_parse = int(c_cup_set_kind_parse(cup_f_c_string(name)))
  end function cup_set_kind_parse

  ! ---- projections ---------------------------------------------------------------

  subroutine cup_setproj_create(sp, S, ierr, opt, errmsg)
    type(cup_setproj_t), intent(out) :: sp
    type(cup_set_t), intent(in) :: S
    integer, intent(out) :: ierr
    type(cup_projector_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_projector_options) :: o
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(S%ptr, 'set projector: set', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call c_cup_projector_options_default(o)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_setproj_create(sp%ptr, S%ptr, o, cmsg)
    if (st == CUP_OK) sp%dim = int(c_cup_set_dim(S%ptr))
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_setproj_create

  subroutine cup_setproj_free(sp)
    type(cup_setproj_t), intent(inout) :: sp
    call c_cup_setproj_free(sp%ptr)
    sp%ptr = c_null_ptr
    sp%dim = 0
  end subroutine cup_setproj_free

  !> Place the set at time t with parameters u (its p entries) and, for a
  !> state-dependent set, the state x; errmsg: what went wrong (C's words,
  !> the one way errors travel), '' on success.
  subroutine cup_setproj_place(sp, t, ierr, u, x, errmsg)
    type(cup_setproj_t), intent(in) :: sp
    real(c_double), intent(in) :: t
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional, target, contiguous :: u(:), x(:)
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    type(c_ptr) :: up, xp
    if (cup_null_fail_(sp%ptr, 'set projector', ierr, errmsg)) return
    up = c_null_ptr
    xp = c_null_ptr
    if (present(u)) then
      if (size(u) > 0) up = c_loc(u)
    end if
    if (present(x)) then
      if (size(x) /= sp%dim) then
        call cup_size_fail_('x', size(x), sp%dim, ierr, errmsg)
        return
      end if
      xp = c_loc(x)
    end if
    cmsg(1) = c_null_char            ! C writes only on an error; a per-step call clears 1 byte, not 12 KB
    call cup_finish_(c_cup_setproj_place(sp%ptr, t, up, xp, cmsg), cmsg, ierr, errmsg)
  end subroutine cup_setproj_place

  !> z = the certified projection of x; ierr: CUP_OK, CUP_WARN_NOT_CERTIFIED
  !> or an error (errmsg: what happened, as cup_setproj_place's).
  subroutine cup_setproj_solve(sp, x, z, ierr, info, errmsg)
    type(cup_setproj_t), intent(in) :: sp
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(inout) :: z(:)
    integer, intent(out) :: ierr
    type(cup_proj_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    type(cup_proj_info) :: pi
    if (cup_null_fail_(sp%ptr, 'set projector', ierr, errmsg)) return
    if (size(x) /= sp%dim .or. size(z) /= sp%dim) then
      call cup_size_fail_('x and z', min(size(x), size(z)), sp%dim, ierr, errmsg)
      return
    end if
    cmsg(1) = c_null_char            ! C writes only on an error; a per-step call clears 1 byte, not 12 KB
    call cup_finish_(c_cup_setproj_solve(sp%ptr, x, z, pi, cmsg), cmsg, ierr, errmsg)
    if (present(info)) info = pi
  end subroutine cup_setproj_solve

  !> The older forms, kept for their users (and their compiled programs):
  !> cup_setproj_place and cup_setproj_solve under their older names, the
  !> same arguments, status and errmsg, as in C (set.h). u and x go on as
  !> they came (CONTIGUOUS to CONTIGUOUS: no copy, absent stays absent).
  subroutine cup_setproj_move(sp, t, ierr, u, x, errmsg)
    type(cup_setproj_t), intent(in) :: sp
    real(c_double), intent(in) :: t
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional, target, contiguous :: u(:), x(:)
    character(len=*), intent(out), optional :: errmsg
    call cup_setproj_place(sp, t, ierr, u, x, errmsg)
  end subroutine cup_setproj_move

  subroutine cup_setproj_project(sp, x, z, ierr, info, errmsg)
    type(cup_setproj_t), intent(in) :: sp
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(inout) :: z(:)
    integer, intent(out) :: ierr
    type(cup_proj_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    call cup_setproj_solve(sp, x, z, ierr, info, errmsg)
  end subroutine cup_setproj_project

  subroutine cup_setproj_set_tolerances(sp, eps_abs, eps_rel, eta_abs, eta_rel, ierr)
    type(cup_setproj_t), intent(in) :: sp
    real(c_double), intent(in) :: eps_abs, eps_rel, eta_abs, eta_rel
    integer, intent(out) :: ierr
    ierr = int(c_cup_setproj_set_tolerances(sp%ptr, eps_abs, eps_rel, eta_abs, eta_rel))
  end subroutine cup_setproj_set_tolerances

  function cup_setproj_message(sp) result(s)
    type(cup_setproj_t), intent(in) :: sp
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_setproj_message(sp%ptr))
  end function cup_setproj_message

  integer function cup_setproj_rows(sp)
    type(cup_setproj_t), intent(in) :: sp
    cup_setproj_rows = int(c_cup_setproj_rows(sp%ptr))
  end function cup_setproj_rows

  integer(c_long) function cup_setproj_rebuilds(sp)
    type(cup_setproj_t), intent(in) :: sp
    cup_setproj_rebuilds = c_cup_setproj_rebuilds(sp%ptr)
  end function cup_setproj_rebuilds

  ! ---- rows of a state-dependent polyset (inside a cup_rows_fn) ---------------------

  !> Append the row  sum_k vals(k) y(cols(k)) + offset >= 0, columns from 1,
  !> increasing. rows is the c_ptr the callback received.
  subroutine cup_rowbuf_add(rows, cols, vals, offset, ierr)
    type(c_ptr), intent(in) :: rows
    integer, intent(in) :: cols(:)
    real(c_double), intent(in) :: vals(:), offset
    integer, intent(out) :: ierr
    integer(c_int) :: c0(size(cols))
    if (size(vals) /= size(cols)) then
      call cup_size_fail_('rows: vals', size(vals), size(cols), ierr)
      return
    end if
    c0 = int(cols - 1, c_int)
    ierr = int(c_cup_rowbuf_add(rows, int(size(cols), c_int), c0, vals, offset))
  end subroutine cup_rowbuf_add

  !> Announce a pattern that may be a row soon (columns from 1).
  subroutine cup_rowbuf_expect(rows, cols, ierr)
    type(c_ptr), intent(in) :: rows
    integer, intent(in) :: cols(:)
    integer, intent(out) :: ierr
    integer(c_int) :: c0(size(cols))
    c0 = int(cols - 1, c_int)
    ierr = int(c_cup_rowbuf_expect(rows, int(size(cols), c_int), c0))
  end subroutine cup_rowbuf_expect

  integer function cup_rowbuf_rows(rows)
    type(c_ptr), intent(in) :: rows
    cup_rowbuf_rows = int(c_cup_rowbuf_rows(rows))
  end function cup_rowbuf_rows
end module catchup_sets
