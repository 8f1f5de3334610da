! Outside Fortran consumer of module catchup_h5run: writes /t and /x.
program consumer_fortran_h5
  use catchup
  use catchup_h5run
  implicit none
  type(cup_h5run_t) :: w
  integer :: ierr
  character(len=CUP_ERRMSG_LEN) :: msg
  call cup_h5run_create(w, 'consumer_fortran_h5.h5', 3, ierr, msg)
  if (ierr /= CUP_OK) then
    write(*, '(a)') trim(msg)
    stop 1
  end if
  call cup_h5run_attr(w, 'note', 'written by the installed Fortran module', ierr)
  call cup_h5run_close(w, ierr, msg)
  if (ierr /= CUP_OK) stop 2
  write(*, '(a,a)') 'consumer_fortran_h5: ', cup_h5_version()
end program consumer_fortran_h5
