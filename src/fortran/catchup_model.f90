! catchup_model -- Fortran wrappers of input.h and lcs.h: the input u(t) and
! the LCS (conventions in catchup_base). Component indices of an input
! (cup_input_add_*: j) are 1-based here, as Fortran users count; every other
! number is the C one (status codes, enum values).
module catchup_model
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char, c_ptr, c_funptr, &
    c_null_ptr, c_loc, c_funloc
  use catchup_constants
  use catchup_types
  use catchup_c
  use catchup_base
  implicit none
  private

  public :: cup_input_create, cup_input_free, cup_input_add, cup_input_add_constant, &
    cup_input_add_sine, cup_input_add_square, cup_input_add_pwl, cup_input_set_callback, &
    cup_input_dim, cup_input_is_constant, cup_input_eval, cup_input_integral, cup_input_next_break, &
    cup_wave_name, cup_wave_parse
  public :: cup_lcs_create, cup_lcs_create_dense, cup_lcs_circuit, cup_lcs_free, cup_lcs_dim, &
    cup_lcs_rows, cup_lcs_inputs, cup_lcs_polyset, cup_lcs_fixed_set, cup_lcs_has_D

contains

  ! ---- input.h ---------------------------------------------------------------------

  !> An input with p components, zero until terms are added.
  subroutine cup_input_create(u, p, ierr, errmsg)
    type(cup_input_t), intent(out) :: u
    integer, intent(in) :: p
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_input_create(u%ptr, int(p, c_int), cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_create

  subroutine cup_input_free(u)
    type(cup_input_t), intent(inout) :: u
    if (.not. u%borrowed) call c_cup_input_free(u%ptr)
    u%ptr = c_null_ptr
    u%borrowed = .false.
  end subroutine cup_input_free

  !> Add the waveform term w to component j (1-based). For a PWL term, w%t
  !> and w%v are c_loc of w%npoints times/values (copied).
  subroutine cup_input_add(u, j, w, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    type(cup_wave), intent(in) :: w
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(u%ptr, 'input', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_input_add(u%ptr, int(j - 1, c_int), w, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_input_add

  !> u_j(t) += value (j 1-based).
  subroutine cup_input_add_constant(u, j, value, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: value
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    w%kind = CUP_WAVE_CONSTANT
    w%value = value
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_constant

  !> u_j(t) += amplitude sin(2 pi frequency t + phase) (16 sin(6 pi t):
  !> amplitude 16, frequency 3).
  subroutine cup_input_add_sine(u, j, amplitude, frequency, ierr, phase, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: amplitude, frequency
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: phase
    character(len=*), intent(out), optional :: errmsg
    call add_periodic(u, j, CUP_WAVE_SINE, amplitude, frequency, ierr, phase, errmsg)
  end subroutine cup_input_add_sine

  !> u_j(t) += amplitude sign(sin(2 pi frequency t + phase)), sign(0) = 0.
  subroutine cup_input_add_square(u, j, amplitude, frequency, ierr, phase, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in) :: amplitude, frequency
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: phase
    character(len=*), intent(out), optional :: errmsg
    call add_periodic(u, j, CUP_WAVE_SQUARE, amplitude, frequency, ierr, phase, errmsg)
  end subroutine cup_input_add_square

  ! A sine or a square wave: amplitude, frequency and an optional phase.
  subroutine add_periodic(u, j, kind, amplitude, frequency, ierr, phase, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    integer(c_int), intent(in) :: kind
    real(c_double), intent(in) :: amplitude, frequency
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: phase
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    w%kind = kind
    w%amplitude = amplitude
    w%frequency = frequency
    if (present(phase)) w%phase = phase
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine add_periodic

  !> u_j(t) += the piecewise-linear function through (t(i), v(i)) (copied).
  subroutine cup_input_add_pwl(u, j, t, v, ierr, errmsg)
    type(cup_input_t), intent(in) :: u
    integer, intent(in) :: j
    real(c_double), intent(in), target, contiguous :: t(:), v(:)
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    type(cup_wave) :: w
    if (size(v) /= size(t)) then
      call cup_size_fail_('PWL: v', size(v), size(t), ierr, errmsg)
      return
    end if
    w%kind = CUP_WAVE_PWL
    w%npoints = int(size(t), c_int)
    if (size(t) > 0) then
      w%t = c_loc(t)
      w%v = c_loc(v)
    end if
    call cup_input_add(u, j, w, ierr, errmsg)
  end subroutine cup_input_add_pwl

  !> Replace the waveforms by the callback fn = c_funloc(f) of a bind(C)
  !> procedure(cup_input_fn); ctx (e.g. c_loc of a user derived type) is
  !> passed to it. Integrals by adaptive quadrature to abs_tol / rel_tol.
  subroutine cup_input_set_callback(u, fn, ctx, abs_tol, rel_tol, ierr)
    type(cup_input_t), intent(in) :: u
    type(c_funptr), value :: fn          ! VALUE: a c_funloc(...) actual needs no static temporary
    type(c_ptr), value :: ctx
    real(c_double), intent(in) :: abs_tol, rel_tol
    integer, intent(out) :: ierr
    if (cup_null_fail_(u%ptr, 'input', ierr)) return
    ierr = int(c_cup_input_set_callback(u%ptr, fn, ctx, abs_tol, rel_tol))
  end subroutine cup_input_set_callback

  integer function cup_input_dim(u)
    type(cup_input_t), intent(in) :: u
    cup_input_dim = int(c_cup_input_dim(u%ptr))
  end function cup_input_dim

  !> .true. if u does not depend on t.
  logical function cup_input_is_constant(u)
    type(cup_input_t), intent(in) :: u
    cup_input_is_constant = c_cup_input_is_constant(u%ptr) /= 0
  end function cup_input_is_constant

  !> out = u(t) (p entries).
  subroutine cup_input_eval(u, t, out, ierr)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: t
    real(c_double), intent(inout) :: out(:)
    integer, intent(out) :: ierr
    if (cup_null_fail_(u%ptr, 'input', ierr)) return
    if (size(out) /= c_cup_input_dim(u%ptr)) then
      call cup_size_fail_('out', size(out), int(c_cup_input_dim(u%ptr)), ierr)
      return
    end if
    ierr = int(c_cup_input_eval(u%ptr, t, out))
  end subroutine cup_input_eval

  !> out = the integral of u over [a, b] (p entries).
  subroutine cup_input_integral(u, a, b, out, ierr)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: a, b
    real(c_double), intent(inout) :: out(:)
    integer, intent(out) :: ierr
    if (cup_null_fail_(u%ptr, 'input', ierr)) return
    if (size(out) /= c_cup_input_dim(u%ptr)) then
      call cup_size_fail_('out', size(out), int(c_cup_input_dim(u%ptr)), ierr)
      return
    end if
    ierr = int(c_cup_input_integral(u%ptr, a, b, out))
  end subroutine cup_input_integral

  !> The next time > t where some term is not smooth (+Inf if none).
  real(c_double) function cup_input_next_break(u, t)
    type(cup_input_t), intent(in) :: u
    real(c_double), intent(in) :: t
    cup_input_next_break = c_cup_input_next_break(u%ptr, t)
  end function cup_input_next_break

  function cup_wave_name(kind) result(s)
    integer, intent(in) :: kind
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_wave_name(int(kind, c_int)))
  end function cup_wave_name

  !> "constant", "sine", "square", "pwl" -> CUP_WAVE_*; -1 if unknown.
  integer function cup_wave_parse(name)
    character(len=*), intent(in) :: name
    cup_wave_parse = int(c_cup_wave_parse(cup_f_c_string(name)))
  end function cup_wave_parse

  ! ---- lcs.h -------------------------------------------------------------------------

  !> An LCS from C views (desc%A%... = cup_csc_view(...) of TARGET matrices).
  subroutine cup_lcs_create(L, desc, ierr, errmsg)
    type(cup_lcs_t), intent(out) :: L
    type(cup_lcs_desc), intent(in) :: desc
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_lcs_create(L%ptr, desc, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_lcs_create

  !> An LCS from dense column-major matrices: A (n x n), B (n x m), C (m x n),
  !> E (n x p), F (m), G (m x p), Pdiag (n). n and m come from C; p from E or
  !> G. A zero-size A, B, E, G is absent (B absent: no P B = C^T check), a
  !> zero-size F is 0, a zero-size Pdiag is P = I. The CSC copies are
  !> released once the C side has copied them.
  subroutine cup_lcs_create_dense(A, B, C, E, F, G, Pdiag, L, ierr, pb_tol, errmsg)
    real(c_double), intent(in) :: A(:, :), B(:, :), C(:, :), E(:, :), G(:, :)
    real(c_double), intent(in), target, contiguous :: F(:), Pdiag(:)
    type(cup_lcs_t), intent(out) :: L
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional :: pb_tol
    character(len=*), intent(out), optional :: errmsg
    type(cup_csc_matrix), target :: cA, cB, cC, cE, cG
    type(cup_lcs_desc) :: d
    integer :: n, m, p
    character(len=200) :: msg
    m = size(C, 1)
    n = size(C, 2)
    p = 0
    if (size(E) > 0) p = size(E, 2)
    if (size(G) > 0) p = size(G, 2)
    if (.not. shape_ok('A', A, n, n)) return
    if (.not. shape_ok('B', B, n, m)) return
    if (.not. shape_ok('E', E, n, p)) return
    if (.not. shape_ok('G', G, m, p)) return
    if (size(F) /= 0 .and. size(F) /= m) then
      call cup_size_fail_('LCS: F', size(F), m, ierr, errmsg)
      return
    end if
    if (size(Pdiag) /= 0 .and. size(Pdiag) /= n) then
      call cup_size_fail_('LCS: Pdiag', size(Pdiag), n, ierr, errmsg)
      return
    end if
    d%n = int(n, c_int)
    d%m = int(m, c_int)
    d%p = int(p, c_int)
    call cup_csc_from_dense(C, cC, ierr)
    d%C = cup_csc_view(cC)
    if (size(A) > 0) then
      call cup_csc_from_dense(A, cA, ierr)
      d%A = cup_csc_view(cA)
    end if
    if (size(B) > 0) then
      call cup_csc_from_dense(B, cB, ierr)
      d%B = cup_csc_view(cB)
    end if
    if (size(E) > 0) then
      call cup_csc_from_dense(E, cE, ierr)
      d%E = cup_csc_view(cE)
    end if
    if (size(G) > 0) then
      call cup_csc_from_dense(G, cG, ierr)
      d%G = cup_csc_view(cG)
    end if
    if (size(F) > 0) d%F = c_loc(F)
    if (size(Pdiag) > 0) then
      d%metric%kind = CUP_METRIC_DIAGONAL
      d%metric%diag = c_loc(Pdiag)
    end if
    if (present(pb_tol)) d%pb_tol = pb_tol
    call cup_lcs_create(L, d, ierr, errmsg)
  contains
    logical function shape_ok(name, X, nr, nc)
      character(len=*), intent(in) :: name
      real(c_double), intent(in) :: X(:, :)
      integer, intent(in) :: nr, nc
      shape_ok = size(X) == 0 .or. (size(X, 1) == nr .and. size(X, 2) == nc)
      if (.not. shape_ok) then
        write(msg, '(a,a,i0,a,i0,a,i0,a,i0)') name, ' is ', size(X, 1), ' x ', size(X, 2), &
          ', expected ', nr, ' x ', nc
        call cup_fail_(CUP_ERR_DIM, 'LCS: ' // trim(msg), ierr, errmsg)
      end if
    end function shape_ok
  end subroutine cup_lcs_create_dense

  !> The paper's circuit (Sec. 7) from its parameters.
  subroutine cup_lcs_circuit(L, c, ierr, errmsg)
    type(cup_lcs_t), intent(out) :: L
    type(cup_circuit), intent(in) :: c
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_lcs_circuit(L%ptr, c, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_lcs_circuit

  subroutine cup_lcs_free(L)
    type(cup_lcs_t), intent(inout) :: L
    if (.not. L%borrowed) call c_cup_lcs_free(L%ptr)
    L%ptr = c_null_ptr
    L%borrowed = .false.
  end subroutine cup_lcs_free

  integer function cup_lcs_dim(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_dim = int(c_cup_lcs_dim(L%ptr))
  end function cup_lcs_dim

  integer function cup_lcs_rows(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_rows = int(c_cup_lcs_rows(L%ptr))
  end function cup_lcs_rows

  integer function cup_lcs_inputs(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_inputs = int(c_cup_lcs_inputs(L%ptr))
  end function cup_lcs_inputs

  !> The set {x : C x + F >= 0} with metric P, owned by L (a borrowed handle).
  function cup_lcs_polyset(L) result(K)
    type(cup_lcs_t), intent(in) :: L
    type(cup_polyset_t) :: K
    K%ptr = c_cup_lcs_polyset(L%ptr)
    K%borrowed = .true.
  end function cup_lcs_polyset

  !> .true. if K does not move with u (G absent or zero).
  logical function cup_lcs_fixed_set(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_fixed_set = c_cup_lcs_fixed_set(L%ptr) /= 0
  end function cup_lcs_fixed_set

  !> .true. when D has a nonzero entry (the theta and adaptive schemes run the LCS).
  logical function cup_lcs_has_D(L)
    type(cup_lcs_t), intent(in) :: L
    cup_lcs_has_D = c_cup_lcs_has_D(L%ptr) /= 0
  end function cup_lcs_has_D

end module catchup_model
