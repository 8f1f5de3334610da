! catchup_h5run -- Fortran wrappers of include/catchup/h5run.h, the HDF5
! writer of one run (/t [N], /x [N, dim]). Like the C header, which
! catchup.h does not include, it is a module of its own in a library of its
! own (catchup_h5_fortran over catchup_h5, built with the apps):
!     use catchup
!     use catchup_h5run
module catchup_h5run
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_null_ptr, &
    c_associated, c_funloc, c_loc, c_int8_t, c_f_pointer
  use catchup_constants
  use catchup_types
  use catchup_base
  use catchup_core, only: cup_integrator_run
  implicit none
  private
  public :: cup_h5run_create, cup_h5run_begin, cup_h5run_commit, cup_h5run_discard, &
    cup_h5run_close, cup_h5run_free, cup_h5run_attr, &
    cup_h5run_attr_double, cup_h5run_attr_long, cup_h5run_attr_string, cup_h5run_flush, &
    cup_h5run_count, cup_h5_version, cup_integrator_run_h5, cup_h5run_signals, cup_h5run_append, &
    cup_h5run_describe, cup_h5run_strings, cup_h5run_dims, &
    cup_h5run_open, cup_h5run_truncate, cup_h5run_put_checkpoint, cup_h5run_get_checkpoint, &
    cup_h5run_drop_checkpoint, cup_h5run_get_string, cup_h5run_get_double, cup_h5run_drop_attr, &
    cup_h5run_status
  public :: cup_h5run_errmsg, c_cup_h5run_errmsg
  ! the C sinks themselves: cup_integrator_run(integ, x0, c_funloc(cup_h5run_sink), w%ptr, ...);
  ! o%on_event = c_funloc(cup_h5run_event), o%event_ctx = w%ptr (adaptive scheme: /events)
  public :: cup_h5run_sink, cup_h5run_event
  public :: c_cup_h5run_create, c_cup_h5run_begin, c_cup_h5run_commit, c_cup_h5run_discard, &
    c_cup_h5run_attr_double, c_cup_h5run_attr_long, &
    c_cup_h5run_attr_string, c_cup_h5run_flush, c_cup_h5run_close, c_cup_h5run_count, &
    c_cup_h5_version, c_cup_h5run_array, c_cup_h5run_signals, c_cup_h5run_append, &
    c_cup_h5run_describe, c_cup_h5run_strings, c_cup_h5run_dims, c_cup_h5run_open, &
    c_cup_h5run_truncate, c_cup_h5run_put_checkpoint, c_cup_h5run_get_checkpoint, c_cup_h5run_drop_checkpoint, &
    c_cup_h5run_get_string, c_cup_h5run_get_double, c_cup_h5run_drop_attr, c_cup_h5run_status

  !> Root attribute: real(c_double), integer (stored as long) or string.
  interface cup_h5run_attr
    module procedure cup_h5run_attr_double, attr_int, cup_h5run_attr_long, cup_h5run_attr_string
  end interface cup_h5run_attr

  interface
    subroutine c_free_(p) bind(C, name="free")
      import :: c_ptr
      type(c_ptr), value :: p
    end subroutine c_free_
  end interface

  ! The raw bind(C) interfaces c_<C name>, generated from the header at build time (gen_bindings.py)
  include "bind_h5run.inc"

contains

  !> Create (truncate) path for states of dimension dim.
  subroutine cup_h5run_create(w, path, dim, ierr, errmsg)
    type(cup_h5run_t), intent(out) :: w
    character(len=*), intent(in) :: path
    integer, intent(in) :: dim
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    call start(w, path, dim, .false., ierr, errmsg)
  end subroutine cup_h5run_create

  !> The same, written to a new sibling of path (PATH.partXXXXXX) that
  !> cup_h5run_commit renames over path: an earlier file stays until then.
  subroutine cup_h5run_begin(w, path, dim, ierr, errmsg)
    type(cup_h5run_t), intent(out) :: w
    character(len=*), intent(in) :: path
    integer, intent(in) :: dim
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    call start(w, path, dim, .true., ierr, errmsg)
  end subroutine cup_h5run_begin

  ! Both starts: the file itself (create) or its staged sibling (begin).
  subroutine start(w, path, dim, staged, ierr, errmsg)
    type(cup_h5run_t), intent(out) :: w
    character(len=*), intent(in) :: path
    integer, intent(in) :: dim
    logical, intent(in) :: staged
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    if (staged) then
      st = c_cup_h5run_begin(w%ptr, cup_f_c_string(path), int(dim, c_int), cmsg)
    else
      st = c_cup_h5run_create(w%ptr, cup_f_c_string(path), int(dim, c_int), cmsg)
    end if
    if (st == CUP_OK) w%dim = dim
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine start

  !> Rename the staged file over its path (after cup_h5run_begin).
  subroutine cup_h5run_commit(w, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_commit(w%ptr))
  end subroutine cup_h5run_commit

  !> Close and free without a word, removing a file not committed.
  subroutine cup_h5run_discard(w)
    type(cup_h5run_t), intent(inout) :: w
    if (c_associated(w%ptr)) call c_cup_h5run_discard(w%ptr)
    w%ptr = c_null_ptr
    w%dim = 0
  end subroutine cup_h5run_discard

  !> Flush, close, free; w%ptr becomes null (closing a null handle is CUP_OK).
  subroutine cup_h5run_close(w, ierr, errmsg)
    type(cup_h5run_t), intent(inout) :: w
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    st = CUP_OK
    cmsg = cup_errbuf_()
    if (c_associated(w%ptr)) st = c_cup_h5run_close(w%ptr, cmsg)
    w%ptr = c_null_ptr
    w%dim = 0
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_h5run_close

  !> Close ignoring the status (for clean-up paths; use cup_h5run_close to
  !> learn whether every sample reached the file).
  subroutine cup_h5run_free(w)
    type(cup_h5run_t), intent(inout) :: w
    integer :: ierr
    call cup_h5run_close(w, ierr)
  end subroutine cup_h5run_free

  subroutine cup_h5run_attr_double(w, name, v, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    real(c_double), intent(in) :: v
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_attr_double(w%ptr, cup_f_c_string(name), v))
  end subroutine cup_h5run_attr_double

  subroutine cup_h5run_attr_long(w, name, v, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    integer(c_long), intent(in) :: v
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_attr_long(w%ptr, cup_f_c_string(name), v))
  end subroutine cup_h5run_attr_long

  subroutine attr_int(w, name, v, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    integer, intent(in) :: v
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_attr_long(w%ptr, cup_f_c_string(name), int(v, c_long)))
  end subroutine attr_int

  subroutine cup_h5run_attr_string(w, name, v, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name, v
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_attr_string(w%ptr, cup_f_c_string(name), cup_f_c_string(v)))
  end subroutine cup_h5run_attr_string

  !> Write what is buffered and flush the file to the OS.
  subroutine cup_h5run_flush(w, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_flush(w%ptr))
  end subroutine cup_h5run_flush

  !> Declare named signals (/signals/<name>, appended with /t by
  !> cup_h5run_append); before the first sample.
  subroutine cup_h5run_signals(w, names, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: names(:)
    integer, intent(out) :: ierr
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    if (size(names) == 0) then
      ierr = CUP_OK
      return
    end if
    call cup_pack_strings_(names, buf, ptrs)
    ierr = int(c_cup_h5run_signals(w%ptr, int(size(names), c_int), c_loc(ptrs)))
  end subroutine cup_h5run_signals

  !> CF attributes of a dataset (path "x", "signals/v(out)"): units and
  !> long_name, each written when present.
  subroutine cup_h5run_describe(w, dataset, ierr, units, long_name)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: dataset
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: units, long_name
    character(kind=c_char, len=:), allocatable, target :: u, l
    type(c_ptr) :: up, lp
    u = cup_f_c_string('')
    l = cup_f_c_string('')
    up = c_null_ptr
    lp = c_null_ptr
    if (present(units)) u = cup_f_c_string(units)
    if (present(long_name)) l = cup_f_c_string(long_name)
    if (present(units)) up = c_loc(u)
    if (present(long_name)) lp = c_loc(l)
    ierr = int(c_cup_h5run_describe(w%ptr, cup_f_c_string(dataset), up, lp))
  end subroutine cup_h5run_describe

  !> A dataset of variable-length UTF-8 strings (labels: a coordinate).
  subroutine cup_h5run_strings(w, name, values, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name, values(:)
    integer, intent(out) :: ierr
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    if (size(values) == 0) then
      ierr = CUP_ERR_ARG
      return
    end if
    call cup_pack_strings_(values, buf, ptrs)
    ierr = int(c_cup_h5run_strings(w%ptr, cup_f_c_string(name), int(size(values), c_long), c_loc(ptrs)))
  end subroutine cup_h5run_strings

  !> Name a dataset's dimensions by dimension scales (one name per axis, in
  !> C order: /x is ['t    ', 'state']).
  subroutine cup_h5run_dims(w, dataset, dims, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: dataset, dims(:)
    integer, intent(out) :: ierr
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    if (size(dims) == 0) then
      ierr = CUP_ERR_ARG
      return
    end if
    call cup_pack_strings_(dims, buf, ptrs)
    ierr = int(c_cup_h5run_dims(w%ptr, cup_f_c_string(dataset), c_loc(ptrs)))
  end subroutine cup_h5run_dims

  !> Append one sample: t, x (dim entries) and the declared signals.
  subroutine cup_h5run_append(w, t, x, ierr, sig)
    type(cup_h5run_t), intent(in) :: w
    real(c_double), intent(in) :: t
    real(c_double), intent(in) :: x(:)
    integer, intent(out) :: ierr
    real(c_double), intent(in), optional, target :: sig(:)
    real(c_double), allocatable, target :: s(:)
    type(c_ptr) :: sp
    sp = c_null_ptr
    if (present(sig)) then
      s = sig
      sp = c_loc(s)
    end if
    ierr = int(c_cup_h5run_append(w%ptr, t, x, sp))
  end subroutine cup_h5run_append

  !> Reopen a stopped run's file to continue it (catchup-run --resume): states
  !> of dimension dim, and the signals `names` in /signals in that order.
  subroutine cup_h5run_open(w, path, dim, ierr, names, errmsg)
    type(cup_h5run_t), intent(out) :: w
    character(len=*), intent(in) :: path
    integer, intent(in) :: dim
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: names(:)
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    type(c_ptr) :: np
    integer(c_int) :: st, ns
    cmsg = cup_errbuf_()
    np = c_null_ptr
    ns = 0
    if (present(names)) then
      if (size(names) > 0) then
        call cup_pack_strings_(names, buf, ptrs)
        np = c_loc(ptrs)
        ns = int(size(names), c_int)
      end if
    end if
    st = c_cup_h5run_open(w%ptr, cup_f_c_string(path), int(dim, c_int), ns, np, cmsg)
    if (st == CUP_OK) w%dim = dim
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_h5run_open

  !> Cut the rows back to `rows` and /events to `events`.
  subroutine cup_h5run_truncate(w, rows, events, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer(c_long), intent(in) :: rows, events
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_truncate(w%ptr, rows, events))
  end subroutine cup_h5run_truncate

  !> Store a checkpoint (cup_integrator_checkpoint_save's blob) as /checkpoint.
  subroutine cup_h5run_put_checkpoint(w, blob, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer(c_int8_t), target, intent(in) :: blob(:)
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_put_checkpoint(w%ptr, c_loc(blob), int(size(blob), c_long)))
  end subroutine cup_h5run_put_checkpoint

  !> The stored checkpoint and the rows and events it covers.
  subroutine cup_h5run_get_checkpoint(w, blob, rows, events, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer(c_int8_t), allocatable, intent(out) :: blob(:)
    integer(c_long), intent(out) :: rows, events
    integer, intent(out) :: ierr
    type(c_ptr) :: p
    integer(c_long) :: n
    integer(c_int8_t), pointer :: b(:)
    ierr = int(c_cup_h5run_get_checkpoint(w%ptr, p, n, rows, events))
    if (ierr /= CUP_OK) return
    call c_f_pointer(p, b, [n])
    blob = b
    call c_free_(p)
  end subroutine cup_h5run_get_checkpoint

  subroutine cup_h5run_drop_checkpoint(w, ierr)
    type(cup_h5run_t), intent(in) :: w
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_drop_checkpoint(w%ptr))
  end subroutine cup_h5run_drop_checkpoint

  !> A root string attribute read back ('' with ierr /= 0 when absent).
  subroutine cup_h5run_get_string(w, name, value, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    character(len=:), allocatable, intent(out) :: value
    integer, intent(out) :: ierr
    type(c_ptr) :: p
    value = ''
    ierr = int(c_cup_h5run_get_string(w%ptr, cup_f_c_string(name), p))
    if (ierr /= CUP_OK) return
    value = cup_c_string(p)
    call c_free_(p)
  end subroutine cup_h5run_get_string

  subroutine cup_h5run_get_double(w, name, v, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    real(c_double), intent(out) :: v
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_get_double(w%ptr, cup_f_c_string(name), v))
  end subroutine cup_h5run_get_double

  subroutine cup_h5run_drop_attr(w, name, ierr)
    type(cup_h5run_t), intent(in) :: w
    character(len=*), intent(in) :: name
    integer, intent(out) :: ierr
    ierr = int(c_cup_h5run_drop_attr(w%ptr, cup_f_c_string(name)))
  end subroutine cup_h5run_drop_attr

  !> Samples written so far.
  integer(c_long) function cup_h5run_count(w)
    type(cup_h5run_t), intent(in) :: w
    cup_h5run_count = c_cup_h5run_count(w%ptr)
  end function cup_h5run_count

  !> The writer's first failure, the one way errors travel: ierr its status
  !> (CUP_OK if nothing failed) and errmsg its words ('' if nothing failed).
  !> A sink returns only a status, so after a run stopped by the writer, ask
  !> here; the writer stops at its first failure, so these words explain
  !> every later refusal too.
  subroutine cup_h5run_status(w, ierr, errmsg)
    type(cup_h5run_t), intent(in) :: w
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    if (cup_null_fail_(w%ptr, 'HDF5 run writer', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    call cup_finish_(c_cup_h5run_status(w%ptr, cmsg), cmsg, ierr, errmsg)
  end subroutine cup_h5run_status

  !> The older form, kept for its users: cup_h5run_status's words ('' if
  !> nothing failed).
  function cup_h5run_errmsg(w) result(s)
    type(cup_h5run_t), intent(in) :: w
    character(len=:), allocatable :: s
    s = ''
    if (c_associated(w%ptr)) s = cup_c_string(c_cup_h5run_errmsg(w%ptr))
  end function cup_h5run_errmsg

  !> "HDF5 1.10.8" of the linked HDF5.
  function cup_h5_version() result(s)
    character(len=:), allocatable :: s
    s = cup_sized_string_(c_cup_h5_version)
  end function cup_h5_version

  !> cup_integrator_run with the states written to w (/t, /x).
  subroutine cup_integrator_run_h5(integ, x0, w, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: x0(:)
    type(cup_h5run_t), intent(in) :: w
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    if (.not. c_associated(w%ptr)) then
      call cup_fail_(CUP_ERR_ARG, 'HDF5 writer handle is null', ierr, errmsg)
      return
    end if
    if (w%dim /= integ%dim) then
      call cup_fail_(CUP_ERR_DIM, 'HDF5 writer and integrator have different dimensions', ierr, errmsg)
      return
    end if
    call cup_integrator_run(integ, x0, c_funloc(cup_h5run_sink), w%ptr, ierr, info, errmsg)
  end subroutine cup_integrator_run_h5
end module catchup_h5run
