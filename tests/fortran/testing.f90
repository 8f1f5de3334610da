! cup_testing -- a few assertions for the Fortran tests: each failure prints
! one line naming the check; `call finish()` stops with status 1 if any failed
! (ctest reads the exit status), 0 otherwise.
module cup_testing
  use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
  use, intrinsic :: iso_c_binding, only: c_double
  implicit none
  private
  public :: check, check_int, check_close, check_contains, check_words, finish, section
  integer, save :: nchecks = 0, nfailed = 0

contains

  subroutine section(name)
    character(len=*), intent(in) :: name
    write(output_unit, '(a,a)') '-- ', name
  end subroutine section

  subroutine check(cond, what)
    logical, intent(in) :: cond
    character(len=*), intent(in) :: what
    nchecks = nchecks + 1
    if (.not. cond) then
      nfailed = nfailed + 1
      write(error_unit, '(a,a)') 'FAILED: ', what
    end if
  end subroutine check

  subroutine check_int(got, want, what)
    integer, intent(in) :: got, want
    character(len=*), intent(in) :: what
    character(len=64) :: buf
    write(buf, '(a,i0,a,i0)') ' (got ', got, ', want ', want
    call check(got == want, what // trim(buf) // ')')
  end subroutine check_int

  subroutine check_close(got, want, tol, what)
    real(c_double), intent(in) :: got, want, tol
    character(len=*), intent(in) :: what
    character(len=120) :: buf
    write(buf, '(a,es24.17,a,es24.17,a,es9.2,a)') ' (got ', got, ', want ', want, ', tol ', tol, ')'
    call check(abs(got - want) <= tol, what // trim(buf))
  end subroutine check_close

  subroutine check_contains(text, part, what)
    character(len=*), intent(in) :: text, part
    character(len=*), intent(in) :: what
    call check(index(text, part) > 0, what // ' ("' // trim(text) // '" should contain "' // part // '")')
  end subroutine check_contains

  !> text is want byte for byte (a Fortran errmsg: want, then blanks only).
  subroutine check_words(text, want, what)
    character(len=*), intent(in) :: text, want
    character(len=*), intent(in) :: what
    call check(len_trim(text) == len(want) .and. text(1:min(len(text), len(want))) == want, &
               what // ' ("' // trim(text) // '" should be "' // want // '")')
  end subroutine check_words

  subroutine finish()
    write(output_unit, '(i0,a,i0,a)') nchecks - nfailed, ' of ', nchecks, ' checks passed'
    if (nfailed > 0) stop 1
  end subroutine finish
end module cup_testing
