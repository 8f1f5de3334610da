! catchup_netlist -- Fortran wrappers of include/catchup/netlist.h: SPICE
! netlists formulated as an LCS, with named signals (docs/netlist.md).
! Re-exported by module `catchup`. Conventions as in catchup_base: ierr last
! among the required arguments, errmsg optional after it, indices from 1.
module catchup_netlist
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_funptr, c_null_ptr, c_associated, &
    c_f_pointer, c_loc
  use catchup_constants
  use catchup_types
  use catchup_c, only: c_cup_lcs_dim, c_cup_lcs_rows, c_cup_lcs_inputs
  use catchup_base
  implicit none
  private
  public :: cup_netlist_load, cup_netlist_load_string, cup_netlist_free, cup_netlist_lcs, cup_netlist_input, &
    cup_netlist_x0, cup_netlist_tran, cup_netlist_state_name, cup_netlist_source, cup_netlist_row_name, cup_netlist_input_name, &
    cup_netlist_row_fixed, cup_netlist_probe, cup_netlist_probe_default, cup_netlist_signal_count, &
    cup_netlist_signal_name, cup_netlist_signal_unit, cup_netlist_signals, cup_netlist_file_count, cup_netlist_file, &
    cup_netlist_tran_window, cup_netlist_tolerances, cup_netlist_warning, cup_netlist_switch_count, &
    cup_netlist_configurations_formed, cup_netlist_set_controller
  public :: c_cup_netlist_switch_count, c_cup_netlist_configurations_formed, c_cup_netlist_set_controller
  public :: c_cup_netlist_file_count, c_cup_netlist_file, c_cup_netlist_tran_window, c_cup_netlist_tolerances, &
    c_cup_netlist_warning
  public :: c_cup_netlist_load, c_cup_netlist_load_string, c_cup_netlist_free, c_cup_netlist_lcs, &
    c_cup_netlist_input, c_cup_netlist_x0, c_cup_netlist_tran, c_cup_netlist_state_name, c_cup_netlist_source, &
    c_cup_netlist_row_name, c_cup_netlist_input_name, c_cup_netlist_row_fixed, c_cup_netlist_probe, &
    c_cup_netlist_probe_default, c_cup_netlist_signal_count, c_cup_netlist_signal_name, &
    c_cup_netlist_signal_unit, c_cup_netlist_signals

  ! The raw bind(C) interfaces c_<C name>, generated from the header at build time (gen_bindings.py)
  include "bind_netlist.inc"

contains

  !> Read and formulate the netlist `path`; sets are "NAME=VALUE" strings
  !> for elements or .params ("R1=2k", "vin=5"), applied before anything is
  !> evaluated.
  subroutine cup_netlist_load(nl, path, ierr, sets, errmsg)
    type(cup_netlist_t), intent(out) :: nl
    character(len=*), intent(in) :: path
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: sets(:)
    character(len=*), intent(out), optional :: errmsg
    call load(nl, ierr, sets, errmsg, path=path)
  end subroutine cup_netlist_load

  !> The same from the netlist's text; `name` stands for the file in messages.
  subroutine cup_netlist_load_string(nl, text, name, ierr, sets, errmsg)
    type(cup_netlist_t), intent(out) :: nl
    character(len=*), intent(in) :: text, name
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: sets(:)
    character(len=*), intent(out), optional :: errmsg
    call load(nl, ierr, sets, errmsg, text=text, name=name)
  end subroutine cup_netlist_load_string

  ! Both loads: the sets as an array of C strings, then the file path or the text.
  subroutine load(nl, ierr, sets, errmsg, path, text, name)
    type(cup_netlist_t), intent(out) :: nl
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: sets(:)
    character(len=*), intent(out), optional :: errmsg
    character(len=*), intent(in), optional :: path, text, name
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    type(c_ptr) :: sp
    integer(c_int) :: ns, st
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    sp = c_null_ptr
    ns = 0
    if (present(sets)) then
      if (size(sets) > 0) then
        call cup_pack_strings_(sets, buf, ptrs)
        sp = c_loc(ptrs)
        ns = int(size(sets), c_int)
      end if
    end if
    cmsg = cup_errbuf_()
    if (present(path)) then
      st = c_cup_netlist_load(nl%ptr, cup_f_c_string(path), sp, ns, cmsg)
    else
      st = c_cup_netlist_load_string(nl%ptr, cup_f_c_string(text), cup_f_c_string(name), sp, ns, cmsg)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine load

  !> Free the netlist (its LCS and input with it) and null the handle; a
  !> borrowed handle (cup_scene_netlist) is only forgotten.
  subroutine cup_netlist_free(nl)
    type(cup_netlist_t), intent(inout) :: nl
    if (.not. nl%borrowed) call c_cup_netlist_free(nl%ptr)
    nl%ptr = c_null_ptr
  end subroutine cup_netlist_free

  !> The LCS, owned by the netlist (a borrowed handle).
  function cup_netlist_lcs(nl) result(L)
    type(cup_netlist_t), intent(in) :: nl
    type(cup_lcs_t) :: L
    if (c_associated(nl%ptr)) L%ptr = c_cup_netlist_lcs(nl%ptr)
    L%borrowed = .true.
  end function cup_netlist_lcs

  !> The sources as an input u(t), owned by the netlist (null when p = 0).
  function cup_netlist_input(nl) result(u)
    type(cup_netlist_t), intent(in) :: nl
    type(cup_input_t) :: u
    if (c_associated(nl%ptr)) u%ptr = c_cup_netlist_input(nl%ptr)
    u%borrowed = .true.
  end function cup_netlist_input

  !> x(0) (n entries) from the initial conditions.
  subroutine cup_netlist_x0(nl, x0, ierr)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), allocatable, intent(out) :: x0(:)
    integer, intent(out) :: ierr
    real(c_double), pointer :: v(:)
    integer :: n
    allocate(x0(0))
    if (cup_null_fail_(nl%ptr, 'netlist', ierr)) return
    n = int(c_cup_lcs_dim(c_cup_netlist_lcs(nl%ptr)))
    call c_f_pointer(c_cup_netlist_x0(nl%ptr), v, [n])
    x0 = v
    ierr = CUP_OK
  end subroutine cup_netlist_x0

  !> .tran TSTEP TSTOP: .true. and the values when the netlist has one.
  logical function cup_netlist_tran(nl, tstep, tstop) result(has)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(out) :: tstep, tstop
    tstep = 0
    tstop = 0
    has = .false.
    if (c_associated(nl%ptr)) has = c_cup_netlist_tran(nl%ptr, tstep, tstop) /= 0
  end function cup_netlist_tran

  !> .tran's TSTART and TMAX (0 where not given): .true. when the netlist has a .tran.
  logical function cup_netlist_tran_window(nl, tstart, tmax) result(has)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(out) :: tstart, tmax
    tstart = 0
    tmax = 0
    has = .false.
    if (c_associated(nl%ptr)) has = c_cup_netlist_tran_window(nl%ptr, tstart, tmax) /= 0
  end function cup_netlist_tran_window

  !> .options RELTOL, ABSTOL, VNTOL, CHGTOL (NaN where not given): .true. when any is given.
  logical function cup_netlist_tolerances(nl, reltol, abstol, vntol, chgtol) result(has)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(out) :: reltol, abstol, vntol, chgtol
    has = c_cup_netlist_tolerances(nl%ptr, reltol, abstol, vntol, chgtol) /= 0
  end function cup_netlist_tolerances

  !> The number of files the netlist was read from (itself, then its .include/.lib files).
  integer function cup_netlist_file_count(nl) result(n)
    type(cup_netlist_t), intent(in) :: nl
    n = 0
    if (c_associated(nl%ptr)) n = int(c_cup_netlist_file_count(nl%ptr))
  end function cup_netlist_file_count

  !> Switches (S, W) in the netlist; a scene's integrator runs them (cup_scene_integrator).
  integer function cup_netlist_switch_count(nl) result(n)
    type(cup_netlist_t), intent(in) :: nl
    n = 0
    if (c_associated(nl%ptr)) n = int(c_cup_netlist_switch_count(nl%ptr))
  end function cup_netlist_switch_count

  !> A digital controller: fn, an integer(c_int) function(t, x, nswitch, gate, ctx) bind(C)
  !> (t and nswitch by value, x(n) and gate(nswitch) arrays, ctx a type(c_ptr) by value),
  !> called every ts with the state; it writes gate (1 closed) to hold until its next call.
  !> c_null_funptr gives the switches back to their controls.
  subroutine cup_netlist_set_controller(nl, ts, fn, ctx, ierr, errmsg)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(in) :: ts
    type(c_funptr), value :: fn
    type(c_ptr), value :: ctx
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    if (cup_null_fail_(nl%ptr, 'netlist', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    call cup_finish_(c_cup_netlist_set_controller(nl%ptr, ts, fn, ctx, cmsg), cmsg, ierr, errmsg)
  end subroutine cup_netlist_set_controller

  !> Switch configurations formulated so far (each once, on its first occurrence).
  integer(c_long) function cup_netlist_configurations_formed(nl) result(n)
    type(cup_netlist_t), intent(in) :: nl
    n = 0
    if (c_associated(nl%ptr)) n = c_cup_netlist_configurations_formed(nl%ptr)
  end function cup_netlist_configurations_formed

  !> File k (1-based; 1 is the netlist itself); '' out of range.
  function cup_netlist_file(nl, k) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: k
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_file(nl%ptr, int(k - 1, c_int)))
  end function cup_netlist_file

  !> Name of state j (1-based): "i(L1)", "v(C1)"; '' out of range.
  function cup_netlist_state_name(nl, j) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: j
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_state_name(nl%ptr, int(j - 1, c_int)))
  end function cup_netlist_state_name

  !> The netlist's text as it was read (before any sets); '' for a null handle.
  function cup_netlist_source(nl) result(s)
    type(cup_netlist_t), intent(in) :: nl
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_source(nl%ptr))
  end function cup_netlist_source

  !> What the formulation allows but warns of (a loop of ideal diodes with
  !> no resistance, named), or '' when nothing.
  function cup_netlist_warning(nl) result(s)
    type(cup_netlist_t), intent(in) :: nl
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_warning(nl%ptr))
  end function cup_netlist_warning

  !> Name of complementarity row i (1-based): the diode.
  function cup_netlist_row_name(nl, i) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_row_name(nl%ptr, int(i - 1, c_int)))
  end function cup_netlist_row_name

  !> Name of input j (1-based): the source.
  function cup_netlist_input_name(nl, j) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: j
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_input_name(nl%ptr, int(j - 1, c_int)))
  end function cup_netlist_input_name

  !> .true. when diode row i (1-based) has its current fixed by the state.
  logical function cup_netlist_row_fixed(nl, i) result(f)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: i
    f = .false.
    if (c_associated(nl%ptr)) f = c_cup_netlist_row_fixed(nl%ptr, int(i - 1, c_int)) /= 0
  end function cup_netlist_row_fixed

  !> Record the signal "v(NODE)", "v(NODE1,NODE2)", "i(ELEMENT)" or "all";
  !> index (optional) is its position among the signals, from 1.
  subroutine cup_netlist_probe(nl, signal, ierr, index, errmsg)
    type(cup_netlist_t), intent(in) :: nl
    character(len=*), intent(in) :: signal
    integer, intent(out) :: ierr
    integer, intent(out), optional :: index
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: k
    if (present(index)) index = 0
    if (cup_null_fail_(nl%ptr, 'netlist', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    k = c_cup_netlist_probe(nl%ptr, cup_f_c_string(signal), cmsg)
    if (k >= 0 .and. present(index)) index = int(k) + 1
    call cup_finish_(min(k, 0_c_int), cmsg, ierr, errmsg)
  end subroutine cup_netlist_probe

  !> The netlist's own .probe lines, or every signal when it has none and
  !> at most `limit` signals exist.
  subroutine cup_netlist_probe_default(nl, limit, ierr, errmsg)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: limit
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    if (cup_null_fail_(nl%ptr, 'netlist', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    call cup_finish_(c_cup_netlist_probe_default(nl%ptr, int(limit, c_int), cmsg), cmsg, ierr, errmsg)
  end subroutine cup_netlist_probe_default

  integer function cup_netlist_signal_count(nl) result(n)
    type(cup_netlist_t), intent(in) :: nl
    n = 0
    if (c_associated(nl%ptr)) n = int(c_cup_netlist_signal_count(nl%ptr))
  end function cup_netlist_signal_count

  !> Name of signal k (1-based): "v(out)", "i(D1)".
  function cup_netlist_signal_name(nl, k) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: k
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_signal_name(nl%ptr, int(k - 1, c_int)))
  end function cup_netlist_signal_name

  !> Unit of signal k (1-based): "V" for a voltage, "A" for a current.
  function cup_netlist_signal_unit(nl, k) result(s)
    type(cup_netlist_t), intent(in) :: nl
    integer, intent(in) :: k
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(nl%ptr)) s = cup_c_string(c_cup_netlist_signal_unit(nl%ptr, int(k - 1, c_int)))
  end function cup_netlist_signal_unit

  !> The signals at time t for state x and, optionally, zeta (m entries,
  !> cup_integrator_zeta; 0 when absent), into out (signal_count entries).
  subroutine cup_netlist_signals(nl, t, x, out, ierr, zeta)
    type(cup_netlist_t), intent(in) :: nl
    real(c_double), intent(in) :: t
    real(c_double), intent(in) :: x(:)
    real(c_double), intent(out) :: out(:)
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional, target :: zeta(:)
    real(c_double), allocatable, target :: z(:)
    type(c_ptr) :: zp
    integer :: n, m
    if (cup_null_fail_(nl%ptr, 'netlist', ierr)) return
    n = int(c_cup_lcs_dim(c_cup_netlist_lcs(nl%ptr)))
    m = int(c_cup_lcs_rows(c_cup_netlist_lcs(nl%ptr)))
    if (size(x) /= n) then
      call cup_size_fail_('x', size(x), n, ierr)
      return
    end if
    if (size(out) /= cup_netlist_signal_count(nl)) then
      call cup_size_fail_('out', size(out), cup_netlist_signal_count(nl), ierr)
      return
    end if
    zp = c_null_ptr
    if (present(zeta)) then
      if (size(zeta) /= m) then
        call cup_size_fail_('zeta', size(zeta), m, ierr)
        return
      end if
      z = zeta
      zp = c_loc(z)
    end if
    ierr = int(c_cup_netlist_signals(nl%ptr, t, x, zp, out))
  end subroutine cup_netlist_signals
end module catchup_netlist
