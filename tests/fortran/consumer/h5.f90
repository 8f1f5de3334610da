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
  ! /x's columns labelled, its dimensions named (t, state), CF attributes
  call cup_h5run_strings(w, 'state', [character(len=5) :: 'q(C4)', 'i(L3)', 'i(L2)'], ierr)
  if (ierr /= CUP_OK) stop 3
  call cup_h5run_dims(w, 'x', [character(len=5) :: 't', 'state'], ierr)
  if (ierr /= CUP_OK) stop 4
  call cup_h5run_describe(w, 'x', ierr, units='C, A, A', long_name='state x(t)')
  if (ierr /= CUP_OK) stop 5
  call cup_h5run_close(w, ierr, msg)
  if (ierr /= CUP_OK) stop 2
  write(*, '(a,a)') 'consumer_fortran_h5: ', cup_h5_version()
end program consumer_fortran_h5
