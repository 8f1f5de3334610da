! catchup_scene -- Fortran wrappers of include/catchup/scene.h (scene files,
! implemented in libcatchup by src/io/scene.c). Re-exported by module
! `catchup` whenever the C library is built with the scene loader.
module catchup_scene
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_null_ptr, &
    c_null_char, c_associated, c_f_pointer, c_loc
  use catchup_constants
  use catchup_types
  use catchup_base
  use catchup_c, only: c_cup_integrator_rows
  use catchup_integrator, only: cup_expected_samples_
  implicit none
  private
  public :: cup_scene_load, cup_scene_load_string, cup_scene_free, cup_scene_name, cup_scene_netlist, &
    cup_scene_lcs, cup_scene_input, cup_scene_x0, cup_scene_options, cup_scene_eps_spec, &
    cup_scene_eta_spec, cup_scene_text, cup_scene_process, cup_scene_dim, cup_scene_integrator, &
    cup_scene_state_name, cup_scene_state_unit, &
    cup_scene_file_count, cup_scene_file, cup_scene_file_sha256, cup_scene_check_output, cup_scene_max_steps, &
    cup_scene_set_time_origin, cup_scene_steady_phase
  public :: c_cup_scene_load, c_cup_scene_load_string, c_cup_scene_free, c_cup_scene_name, c_cup_scene_netlist, &
    c_cup_scene_lcs, c_cup_scene_input, c_cup_scene_x0, c_cup_scene_options, &
    c_cup_scene_eps_spec, c_cup_scene_eta_spec, c_cup_scene_text, c_cup_scene_process, &
    c_cup_scene_dim, c_cup_scene_integrator, c_cup_scene_crowd, c_cup_scene_state_label, c_cup_scene_file_count, &
    c_cup_scene_file, c_cup_scene_file_sha256, c_cup_scene_check_output, c_cup_scene_max_steps

  ! The raw bind(C) interfaces c_<C name>, generated from the header at build time (gen_bindings.py)
  include "bind_scene.inc"

contains


  !> Load the scene file `path`; overrides are "dotted.key=value" strings
  !> ("circuit.R1=2", "n=1000") applied before the document is read.
  subroutine cup_scene_load(s, path, ierr, overrides, errmsg)
    type(cup_scene_t), intent(out) :: s
    character(len=*), intent(in) :: path
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: overrides(:)
    character(len=*), intent(out), optional :: errmsg
    call load(s, ierr, overrides, errmsg, path=path)
  end subroutine cup_scene_load

  !> The same from YAML text; `name` stands for the file name in messages and
  !> `dir` (default: the working directory) is where Matrix Market files are.
  subroutine cup_scene_load_string(s, text, name, ierr, dir, overrides, errmsg)
    type(cup_scene_t), intent(out) :: s
    character(len=*), intent(in) :: text, name
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: dir
    character(len=*), intent(in), optional :: overrides(:)
    character(len=*), intent(out), optional :: errmsg
    call load(s, ierr, overrides, errmsg, text=text, name=name, dir=dir)
  end subroutine cup_scene_load_string

  ! Both loads: the overrides as an array of C strings, then the file path or
  ! the text (with its name and the optional directory, NULL when absent).
  subroutine load(s, ierr, overrides, errmsg, path, text, name, dir)
    type(cup_scene_t), intent(out) :: s
    integer, intent(out) :: ierr
    character(len=*), intent(in), optional :: overrides(:)
    character(len=*), intent(out), optional :: errmsg
    character(len=*), intent(in), optional :: path, text, name, dir
    character(kind=c_char), allocatable, target :: buf(:, :)
    type(c_ptr), allocatable, target :: ptrs(:)
    character(kind=c_char, len=:), allocatable, target :: cdir
    type(c_ptr) :: op, dp
    integer(c_int) :: nov, st
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    op = c_null_ptr
    nov = 0
    if (present(overrides)) then
      if (size(overrides) > 0) then
        call cup_pack_strings_(overrides, buf, ptrs)
        op = c_loc(ptrs)
        nov = int(size(overrides), c_int)
      end if
    end if
    cmsg = cup_errbuf_()
    if (present(path)) then
      st = c_cup_scene_load(s%ptr, cup_f_c_string(path), op, nov, cmsg)
    else
      dp = c_null_ptr
      if (present(dir)) then
        cdir = cup_f_c_string(dir)
        dp = c_loc(cdir)
      end if
      st = c_cup_scene_load_string(s%ptr, cup_f_c_string(text), cup_f_c_string(name), dp, op, nov, cmsg)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine load

  !> Free the scene (its LCS, input and options with it) and null the handle.
  subroutine cup_scene_free(s)
    type(cup_scene_t), intent(inout) :: s
    call c_cup_scene_free(s%ptr)
    s%ptr = c_null_ptr
  end subroutine cup_scene_free

  function cup_scene_name(s) result(text)
    type(cup_scene_t), intent(in) :: s
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_name(s%ptr))
  end function cup_scene_name

  !> The scene's netlist when its model is `netlist:` (a null handle
  !> otherwise), owned by the scene (a borrowed handle).
  function cup_scene_netlist(s) result(nl)
    type(cup_scene_t), intent(in) :: s
    type(cup_netlist_t) :: nl
    if (c_associated(s%ptr)) nl%ptr = c_cup_scene_netlist(s%ptr)
    nl%borrowed = .true.
  end function cup_scene_netlist

  !> The scene's LCS, owned by the scene (a borrowed handle).
  function cup_scene_lcs(s) result(L)
    type(cup_scene_t), intent(in) :: s
    type(cup_lcs_t) :: L
    if (c_associated(s%ptr)) L%ptr = c_cup_scene_lcs(s%ptr)
    L%borrowed = .true.
  end function cup_scene_lcs

  !> The scene's input, owned by the scene (null pointer when p = 0).
  function cup_scene_input(s) result(u)
    type(cup_scene_t), intent(in) :: s
    type(cup_input_t) :: u
    if (c_associated(s%ptr)) u%ptr = c_cup_scene_input(s%ptr)
    u%borrowed = .true.
  end function cup_scene_input

  !> x0 (n entries) of the scene.
  subroutine cup_scene_x0(s, x0, ierr)
    type(cup_scene_t), intent(in) :: s
    real(c_double), allocatable, intent(out) :: x0(:)
    integer, intent(out) :: ierr
    real(c_double), pointer :: v(:)
    type(c_ptr) :: p
    integer :: n
    allocate(x0(0))
    ierr = CUP_ERR_ARG
    if (.not. c_associated(s%ptr)) return
    n = int(c_cup_scene_dim(s%ptr))
    p = c_cup_scene_x0(s%ptr)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, v, [n])
    x0 = v
    ierr = CUP_OK
  end subroutine cup_scene_x0

  !> The state dimension, for an LCS scene or a set: scene.
  integer function cup_scene_dim(s)
    type(cup_scene_t), intent(in) :: s
    cup_scene_dim = 0
    if (c_associated(s%ptr)) cup_scene_dim = int(c_cup_scene_dim(s%ptr))
  end function cup_scene_dim

  !> The name of state component j (1-based): "q(C4)" for the paper's
  !> circuit, a netlist's "v(C1)", a crowd's "x0", else "x1"; '' out of range.
  function cup_scene_state_name(s, j) result(name)
    type(cup_scene_t), intent(in) :: s
    integer, intent(in) :: j
    character(len=:), allocatable :: name
    character(len=:), allocatable :: unit
    call state_label(s, j, name, unit)
  end function cup_scene_state_name

  !> The unit of state component j (1-based): "C", "A", "V", "m", or "1"
  !> (the model's own units); '' out of range.
  function cup_scene_state_unit(s, j) result(unit)
    type(cup_scene_t), intent(in) :: s
    integer, intent(in) :: j
    character(len=:), allocatable :: unit
    character(len=:), allocatable :: name
    call state_label(s, j, name, unit)
  end function cup_scene_state_unit

  subroutine state_label(s, j, name, unit)
    type(cup_scene_t), intent(in) :: s
    integer, intent(in) :: j
    character(len=:), allocatable, intent(inout) :: name, unit
    character(kind=c_char) :: buf(256)
    type(c_ptr) :: up
    buf = c_null_char
    up = c_null_ptr
    name = ''
    unit = ''
    if (.not. c_associated(s%ptr)) return
    if (c_cup_scene_state_label(s%ptr, int(j - 1, c_int), buf, int(size(buf), c_long), up) /= CUP_OK) return
    name = cup_chars_to_string(buf)
    unit = cup_c_string(up)
  end subroutine state_label

  !> A set: scene's process (its set and input are the scene's: use them while
  !> the scene lives); found = .false. for an LCS scene.
  subroutine cup_scene_process(s, d, found)
    type(cup_scene_t), intent(in) :: s
    type(cup_process_desc), intent(out) :: d
    logical, intent(out) :: found
    type(cup_process_desc), pointer :: dp
    type(c_ptr) :: p
    found = .false.
    if (.not. c_associated(s%ptr)) return
    p = c_cup_scene_process(s%ptr)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, dp)
    d = dp
    found = .true.
  end subroutine cup_scene_process

  !> An integrator for the scene's model (an LCS or a process), with the
  !> scene's options or opt.
  subroutine cup_scene_integrator(s, integ, ierr, opt, errmsg)
    type(cup_scene_t), intent(in) :: s
    type(cup_integrator_t), intent(out) :: integ
    integer, intent(out) :: ierr
    type(cup_integrator_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_integrator_options) :: o
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(s%ptr, 'scene', ierr, errmsg)) return
    if (present(opt)) then
      o = opt
    else
      call cup_scene_options(s, o, ierr)
    end if
    cmsg = cup_errbuf_()
    st = c_cup_scene_integrator(s%ptr, o, integ%ptr, cmsg)
    if (st == CUP_OK) then
      integ%dim = int(c_cup_scene_dim(s%ptr))
      integ%rows = int(c_cup_integrator_rows(integ%ptr))
      integ%expected = cup_expected_samples_(o)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_scene_integrator

  !> The integrator options of the scene (T, n, eps, eta, scheme, ...), a copy.
  subroutine cup_scene_options(s, o, ierr)
    type(cup_scene_t), intent(in) :: s
    type(cup_integrator_options), intent(out) :: o
    integer, intent(out) :: ierr
    type(cup_integrator_options), pointer :: op
    type(c_ptr) :: p
    ierr = CUP_ERR_ARG
    if (.not. c_associated(s%ptr)) return
    p = c_cup_scene_options(s%ptr)
    if (.not. c_associated(p)) return
    call c_f_pointer(p, op)
    o = op
    ierr = CUP_OK
  end subroutine cup_scene_options

  !> eps as written in the scene, e.g. "n^-2.1".
  function cup_scene_eps_spec(s) result(text)
    type(cup_scene_t), intent(in) :: s
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_eps_spec(s%ptr))
  end function cup_scene_eps_spec

  function cup_scene_eta_spec(s) result(text)
    type(cup_scene_t), intent(in) :: s
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_eta_spec(s%ptr))
  end function cup_scene_eta_spec

  !> The document after overrides, as YAML text.
  function cup_scene_text(s) result(text)
    type(cup_scene_t), intent(in) :: s
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_text(s%ptr))
  end function cup_scene_text

  !> How many files the scene was read from (the scene file, its Matrix
  !> Market files, its netlist and what that includes).
  integer function cup_scene_file_count(s) result(n)
    type(cup_scene_t), intent(in) :: s
    n = 0
    if (c_associated(s%ptr)) n = int(c_cup_scene_file_count(s%ptr))
  end function cup_scene_file_count

  !> File k (1-based) as it was opened ('' out of range).
  function cup_scene_file(s, k) result(text)
    type(cup_scene_t), intent(in) :: s
    integer, intent(in) :: k
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_file(s%ptr, int(k - 1, c_int)))
  end function cup_scene_file

  !> The SHA-256 (hex) of the bytes of file k (1-based) that were read.
  function cup_scene_file_sha256(s, k) result(text)
    type(cup_scene_t), intent(in) :: s
    integer, intent(in) :: k
    character(len=:), allocatable :: text
    text = ''
    if (c_associated(s%ptr)) text = cup_c_string(c_cup_scene_file_sha256(s%ptr, int(k - 1, c_int)))
  end function cup_scene_file_sha256

  !> ierr = CUP_ERR_ARG (errmsg names both) when `path` is one of the files
  !> the scene was read from (the same path resolved, or the same file).
  subroutine cup_scene_check_output(s, path, ierr, errmsg)
    type(cup_scene_t), intent(in) :: s
    character(len=*), intent(in) :: path
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    cmsg = c_null_char
    ierr = int(c_cup_scene_check_output(s%ptr, cup_f_c_string(path), cmsg))
    if (present(errmsg)) errmsg = cup_chars_to_string(cmsg)
  end subroutine cup_scene_check_output

  !> The scene's max_steps: the most steps a fixed-step run of it may take.
  function cup_scene_max_steps(s) result(n)
    type(cup_scene_t), intent(in) :: s
    integer(c_long) :: n
    n = c_cup_scene_max_steps(s%ptr)
  end function cup_scene_max_steps
  !> The scene's sources read from t0 on (scene.h): make integrators after.
  subroutine cup_scene_set_time_origin(sc, t0, ierr, errmsg)
    type(cup_scene_t), intent(in) :: sc
    real(c_double), intent(in) :: t0
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(sc%ptr, 'scene', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_scene_set_time_origin(sc%ptr, t0, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_scene_set_time_origin

  !> The scene's steady-state period T (period: the one asked for, or 0) and
  !> phase t0, its sources then read from t0 on (scene.h).
  subroutine cup_scene_steady_phase(sc, period, T, t0, ierr, errmsg)
    type(cup_scene_t), intent(in) :: sc
    real(c_double), intent(in) :: period
    real(c_double), intent(out) :: T, t0
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    T = 0
    t0 = 0
    if (cup_null_fail_(sc%ptr, 'scene', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    st = c_cup_scene_steady_phase(sc%ptr, period, T, t0, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_scene_steady_phase

end module catchup_scene
