! catchup_base -- strings across the C boundary, status codes, versions and
! sparse matrices (status.h, version.h, sparse.h) for the Fortran module
! `catchup`. Conventions of every wrapper (README, "Fortran quick start"):
! `ierr` last among the required arguments (the C status: 0 ok, < 0 error,
! > 0 warning), then the optional ones (`errmsg` gets the C message, or the
! status text when C gave none, or '' on success). Arrays the C side reads
! or writes are checked against the sizes the C side expects before the call.
module catchup_base
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_size_t, c_double, c_char, c_ptr, &
    c_null_ptr, c_null_char, c_associated, c_f_pointer, c_loc
  use catchup_constants
  use catchup_types
  use catchup_c
  implicit none
  private

  public :: cup_c_string, cup_f_c_string, cup_chars_to_string
  public :: cup_status_string, cup_status_name, cup_status_merge
  public :: cup_version, cup_dependency_versions
  public :: cup_csc_from_fortran, cup_csc_from_dense, cup_csc_view, cup_csc_free
  ! for the other modules of the binding (not part of the documented API)
  public :: cup_finish_, cup_fail_, cup_errbuf_, cup_size_fail_, cup_null_fail_, cup_copy_out_, &
    cup_pack_strings_, cup_sized_string_

  !> `int f(char *buf, unsigned long size)`: writes at most size bytes, NUL
  !> included, and returns the full length (snprintf's contract).
  abstract interface
    function cup_sized_fn(buf, size) bind(C) result(n)
      import :: c_int, c_long, c_char
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_long), value :: size
      integer(c_int) :: n
    end function cup_sized_fn
  end interface

contains

  ! ---- strings ---------------------------------------------------------------

  !> The NUL-terminated C string at p as a Fortran string ('' for a null p).
  function cup_c_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable :: s
    character(kind=c_char), pointer :: chars(:)
    integer :: n, i
    if (.not. c_associated(p)) then
      s = ''
      return
    end if
    n = int(c_strlen(p))
    call c_f_pointer(p, chars, [n])
    allocate(character(len=n) :: s)
    do i = 1, n
      s(i:i) = chars(i)
    end do
  end function cup_c_string

  !> trim(s)//c_null_char: a Fortran string for a `const char *` argument.
  function cup_f_c_string(s) result(c)
    character(len=*), intent(in) :: s
    character(kind=c_char, len=:), allocatable :: c
    c = trim(s) // c_null_char
  end function cup_f_c_string

  !> A NUL-terminated character array (a C buffer, cup_run_info%message) as a
  !> Fortran string.
  function cup_chars_to_string(chars) result(s)
    character(kind=c_char), intent(in) :: chars(:)
    character(len=:), allocatable :: s
    integer :: n, i
    n = 0
    do while (n < size(chars))
      if (chars(n + 1) == c_null_char) exit
      n = n + 1
    end do
    allocate(character(len=n) :: s)
    do i = 1, n
      s(i:i) = chars(i)
    end do
  end function cup_chars_to_string

  !> An empty C error buffer of CUP_ERRMSG_LEN bytes.
  pure function cup_errbuf_() result(b)
    character(kind=c_char) :: b(CUP_ERRMSG_LEN)
    b = c_null_char
  end function cup_errbuf_

  !> ierr = st; errmsg = the C message (or the status text if C wrote none).
  subroutine cup_finish_(st, cmsg, ierr, errmsg)
    integer(c_int), intent(in) :: st
    character(kind=c_char), intent(in) :: cmsg(:)
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    ierr = int(st)
    if (.not. present(errmsg)) return
    errmsg = ''
    if (st == CUP_OK) return
    errmsg = cup_chars_to_string(cmsg)
    if (len_trim(errmsg) == 0) errmsg = cup_status_string(st)
  end subroutine cup_finish_

  !> A failure found by the wrapper itself (sizes, null handles).
  subroutine cup_fail_(st, what, ierr, errmsg)
    integer(c_int), intent(in) :: st
    character(len=*), intent(in) :: what
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    ierr = int(st)
    if (present(errmsg)) errmsg = what
  end subroutine cup_fail_

  ! ---- status.h --------------------------------------------------------------

  !> Message for a status code ("unknown status" for a value not in the list).
  function cup_status_string(status) result(s)
    integer, intent(in) :: status
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_status_string(int(status, c_int)))
  end function cup_status_string

  !> Symbolic name ("CUP_ERR_EMPTY_SET"; "CUP_UNKNOWN" if not in the list).
  function cup_status_name(status) result(s)
    integer, intent(in) :: status
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_status_name(int(status, c_int)))
  end function cup_status_name

  !> Most severe of two statuses (any error beats any warning beats ok; among
  !> errors, or warnings, the first is kept). Restated in Fortran so that it
  !> can be elemental; tests/fortran compares it with the C function.
  elemental function cup_status_merge(first, second) result(st)
    integer, intent(in) :: first, second
    integer :: st
    if (first < 0) then
      st = first
    else if (second < 0) then
      st = second
    else if (first > 0) then
      st = first
    else
      st = second
    end if
  end function cup_status_merge

  ! ---- version.h -------------------------------------------------------------

  !> Version of the library actually linked ("MAJOR.MINOR.PATCH"); compare
  !> with CUP_VERSION_STRING (the headers the module was built from).
  function cup_version() result(s)
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_version())
  end function cup_version

  !> "catchup 0.1.0; CHOLMOD 3.0.14; GSL 2.7.1; libyaml 0.2.5" (linked libraries).
  function cup_dependency_versions() result(s)
    character(len=:), allocatable :: s
    s = cup_sized_string_(c_cup_dependency_versions)
  end function cup_dependency_versions

  !> The whole string a cup_sized_fn writes: its length first, from a one-byte
  !> probe, then the string into a buffer of that size.
  function cup_sized_string_(fn) result(s)
    procedure(cup_sized_fn) :: fn
    character(len=:), allocatable :: s
    character(kind=c_char) :: probe(1)
    character(kind=c_char), allocatable :: buf(:)
    integer(c_int) :: n
    n = fn(probe, 1_c_long)
    allocate(buf(max(n, 0) + 1))
    n = fn(buf, int(size(buf), c_long))
    s = cup_chars_to_string(buf)
  end function cup_sized_string_

  ! ---- sparse.h: Fortran-owned 0-based CSC copies ------------------------------

  !> Copy a CSC matrix given with `base`-based indices (default 1, the Fortran
  !> habit) into csc, 0-based, never altering the caller's arrays. Checks that
  !> colptr(1) = base, colptr is nondecreasing, the arrays hold colptr(ncol+1)
  !> - base entries and every row index is in range. Free with cup_csc_free
  !> (or let csc go out of scope) once the C create function has copied it.
  subroutine cup_csc_from_fortran(colptr, rowind, values, nrow, ncol, csc, ierr, base, errmsg)
    integer(c_int), intent(in) :: colptr(:), rowind(:)
    real(c_double), intent(in) :: values(:)
    integer, intent(in) :: nrow, ncol
    type(cup_csc_matrix), intent(out) :: csc
    integer, intent(out) :: ierr
    integer, intent(in), optional :: base
    character(len=*), intent(out), optional :: errmsg
    integer :: b, j, k, nnz
    character(len=160) :: what
    b = 1
    if (present(base)) b = base
    if (nrow < 0 .or. ncol < 0) then
      write(what, '(a,i0,a,i0,a)') 'CSC: nrow = ', nrow, ', ncol = ', ncol, ' must be >= 0'
      call cup_fail_(CUP_ERR_ARG, trim(what), ierr, errmsg)
      return
    end if
    if (size(colptr) /= ncol + 1) then
      write(what, '(a,i0,a,i0)') 'CSC: colptr has ', size(colptr), ' entries, expected ncol+1 = ', ncol + 1
      call cup_fail_(CUP_ERR_DIM, trim(what), ierr, errmsg)
      return
    end if
    if (colptr(1) /= b) then
      write(what, '(a,i0,a,i0)') 'CSC: colptr(1) = ', colptr(1), ' but the base is ', b
      call cup_fail_(CUP_ERR_ARG, trim(what), ierr, errmsg)
      return
    end if
    do j = 1, ncol
      if (colptr(j + 1) < colptr(j)) then
        write(what, '(a,i0,a)') 'CSC: colptr decreases at column ', j, ' (1-based)'
        call cup_fail_(CUP_ERR_ARG, trim(what), ierr, errmsg)
        return
      end if
    end do
    nnz = colptr(ncol + 1) - b
    if (size(rowind) < nnz .or. size(values) < nnz) then
      write(what, '(a,i0,a,i0,a,i0,a)') 'CSC: ', nnz, ' nonzeros but rowind has ', size(rowind), &
        ' and values ', size(values), ' entries'
      call cup_fail_(CUP_ERR_DIM, trim(what), ierr, errmsg)
      return
    end if
    do k = 1, nnz
      if (rowind(k) < b .or. rowind(k) >= b + nrow) then
        write(what, '(a,i0,a,i0,a,i0,a,i0,a)') 'CSC: rowind(', k, ') = ', rowind(k), &
          ' outside [', b, ', ', b + nrow - 1, ']'
        call cup_fail_(CUP_ERR_ARG, trim(what), ierr, errmsg)
        return
      end if
    end do
    csc%nrow = int(nrow, c_int)
    csc%ncol = int(ncol, c_int)
    allocate(csc%colptr(ncol + 1), csc%rowind(max(nnz, 1)), csc%values(max(nnz, 1)))
    csc%colptr = colptr(1:ncol + 1) - b
    csc%rowind = 0
    csc%values = 0
    csc%rowind(1:nnz) = rowind(1:nnz) - b
    csc%values(1:nnz) = values(1:nnz)
    call cup_fail_(CUP_OK, '', ierr, errmsg)
  end subroutine cup_csc_from_fortran

  !> The nonzeros of a dense column-major matrix A as a 0-based CSC copy
  !> (an entry is stored when A(i,j) /= 0, so a NaN is kept for the C side
  !> to reject).
  subroutine cup_csc_from_dense(A, csc, ierr)
    real(c_double), intent(in) :: A(:, :)
    type(cup_csc_matrix), intent(out) :: csc
    integer, intent(out) :: ierr
    integer :: i, j, nnz
    nnz = count(A /= 0)
    csc%nrow = int(size(A, 1), c_int)
    csc%ncol = int(size(A, 2), c_int)
    allocate(csc%colptr(size(A, 2) + 1), csc%rowind(max(nnz, 1)), csc%values(max(nnz, 1)))
    csc%rowind = 0
    csc%values = 0
    nnz = 0
    csc%colptr(1) = 0
    do j = 1, size(A, 2)
      do i = 1, size(A, 1)
        if (A(i, j) /= 0) then
          nnz = nnz + 1
          csc%rowind(nnz) = int(i - 1, c_int)
          csc%values(nnz) = A(i, j)
        end if
      end do
      csc%colptr(j + 1) = int(nnz, c_int)
    end do
    ierr = CUP_OK
  end subroutine cup_csc_from_dense

  !> The C view (cup_csc) of a Fortran-owned CSC copy; an unallocated
  !> cup_csc_matrix gives the all-zero view, which the LCS reads as "absent".
  !> The view points into csc: csc must have the TARGET attribute and outlive
  !> every use of the view.
  function cup_csc_view(csc) result(v)
    type(cup_csc_matrix), intent(in), target :: csc
    type(cup_csc) :: v
    v = cup_csc()
    if (.not. allocated(csc%colptr)) return
    v%nrow = csc%nrow
    v%ncol = csc%ncol
    v%colptr = c_loc(csc%colptr)
    v%rowind = c_loc(csc%rowind)
    v%values = c_loc(csc%values)
  end function cup_csc_view

  !> Release a Fortran-owned CSC copy (harmless on an empty one).
  subroutine cup_csc_free(csc)
    type(cup_csc_matrix), intent(inout) :: csc
    if (allocated(csc%colptr)) deallocate(csc%colptr)
    if (allocated(csc%rowind)) deallocate(csc%rowind)
    if (allocated(csc%values)) deallocate(csc%values)
    csc%nrow = 0
    csc%ncol = 0
  end subroutine cup_csc_free

  ! ---- checks shared by the wrappers (catchup_projector, _model, _integrator) -

  !> ierr = CUP_ERR_DIM with "<what> has <got> entries, expected <want>".
  subroutine cup_size_fail_(what, got, want, ierr, errmsg)
    character(len=*), intent(in) :: what
    integer, intent(in) :: got, want
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(len=200) :: msg
    write(msg, '(a,a,i0,a,i0)') what, ' has ', got, ' entries, expected ', want
    call cup_fail_(CUP_ERR_DIM, trim(msg), ierr, errmsg)
  end subroutine cup_size_fail_

  logical function cup_null_fail_(p, what, ierr, errmsg)
    type(c_ptr), intent(in) :: p
    character(len=*), intent(in) :: what
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    cup_null_fail_ = .not. c_associated(p)
    if (cup_null_fail_) then
      call cup_fail_(CUP_ERR_ARG, what // ' handle is null', ierr, errmsg)
    else
      ierr = CUP_OK
    end if
  end function cup_null_fail_

  !> Copy n doubles from a C pointer (null: found = .false.).
  subroutine cup_copy_out_(p, n, out, found, ierr)
    type(c_ptr), intent(in) :: p
    integer, intent(in) :: n
    real(c_double), intent(inout) :: out(:)
    logical, intent(out) :: found
    integer, intent(out) :: ierr
    real(c_double), pointer :: v(:)
    found = c_associated(p)
    ierr = CUP_OK
    if (size(out) < n) then
      ierr = CUP_ERR_DIM
      return
    end if
    if (.not. found) return
    call c_f_pointer(p, v, [n])
    out(1:n) = v
  end subroutine cup_copy_out_

  !> NUL-terminated copies of the trimmed strings (scene overrides, netlist
  !> sets), one per column of buf, and the array of pointers to them
  !> (const char *const *).
  subroutine cup_pack_strings_(overrides, buf, ptrs)
    character(len=*), intent(in) :: overrides(:)
    character(kind=c_char), allocatable, target, intent(out) :: buf(:, :)
    type(c_ptr), allocatable, target, intent(out) :: ptrs(:)
    integer :: i, k, n
    allocate(buf(len(overrides) + 1, size(overrides)), ptrs(size(overrides)))
    buf = c_null_char
    do i = 1, size(overrides)
      n = len_trim(overrides(i))
      do k = 1, n
        buf(k, i) = overrides(i)(k:k)
      end do
      ptrs(i) = c_loc(buf(1, i))
    end do
  end subroutine cup_pack_strings_

  ! Optional array arguments are copied into local allocatables before their
  ! address goes to C (creation-time data, copied by C anyway): gfortran 12
  ! at -O2 crashes when an absent optional assumed-shape actual is forwarded
  ! to an OPTIONAL, CONTIGUOUS dummy, and users do forward optionals.

end module catchup_base
