! test_f_h5run -- the HDF5 writer's errors from Fortran (module
! catchup_h5run), the one way they travel: cup_h5run_status gives CUP_OK and
! '' while nothing failed, then the first failure's status and C's words
! byte for byte (the text of tests/test_h5run.c's test_status_one_way), the
! same words as the older cup_h5run_errmsg; a null handle is CUP_ERR_ARG.
! cup_h5run_begin stages the file: nothing at its path until the commit, the
! dimension kept as cup_h5run_create keeps it.
!   test_f_h5run DIR   (the files are DIR/f_status.h5, DIR/f_staged.h5)
program test_f_h5run
  use catchup
  use catchup_h5run
  use cup_testing
  implicit none
  type(cup_h5run_t) :: w
  character(len=CUP_ERRMSG_LEN) :: msg, closed
  character(len=4096) :: dir
  integer :: ierr, iclose, unit
  logical :: there
  character(len=*), parameter :: words = "h5run: signal 0: 'a/b' is not a dataset name"

  call get_command_argument(1, dir)
  call section('cup_h5run_status: nothing failed, then a refused signal name')
  call cup_h5run_create(w, trim(dir) // '/f_status.h5', 2, ierr, msg)
  call check_int(ierr, CUP_OK, 'created: ' // trim(msg))
  msg = 'untouched'
  call cup_h5run_status(w, ierr, msg)
  call check_int(ierr, CUP_OK, 'nothing failed yet')
  call check_words(msg, '', 'no words')
  call check_words(cup_h5run_errmsg(w), '', 'the older form: no words either')
  call cup_h5run_signals(w, ['a/b'], ierr)
  call check_int(ierr, CUP_ERR_ARG, 'a signal name with a slash is refused')
  call cup_h5run_status(w, ierr, msg)
  call check_int(ierr, CUP_ERR_ARG, 'the status of the first failure')
  call check_words(msg, words, 'its words')
  call check_words(cup_h5run_errmsg(w), words, 'the older cup_h5run_errmsg, the same words')
  call cup_h5run_status(w, ierr)
  call check_int(ierr, CUP_ERR_ARG, 'without errmsg: the same status')
  call cup_h5run_close(w, iclose, closed)
  call check_int(iclose, CUP_OK, 'close: the file itself is sound')
  call check_words(closed, '', 'close: no words')

  call section('cup_h5run_status of a closed (null) handle')
  call cup_h5run_status(w, ierr, msg)
  call check_int(ierr, CUP_ERR_ARG, 'a null handle')
  call check_words(msg, 'HDF5 run writer handle is null', 'the wrapper''s words')

  call section('cup_h5run_begin: staged beside its path until cup_h5run_commit')
  open(newunit=unit, file=trim(dir) // '/f_staged.h5')
  close(unit, status='delete')
  call cup_h5run_begin(w, trim(dir) // '/f_staged.h5', 3, ierr, msg)
  call check_int(ierr, CUP_OK, 'begun: ' // trim(msg))
  call check_int(w%dim, 3, 'the dimension kept')
  inquire(file=trim(dir) // '/f_staged.h5', exist=there)
  call check(.not. there, 'nothing at the path before the commit')
  call cup_h5run_commit(w, ierr)
  call check_int(ierr, CUP_OK, 'committed')
  inquire(file=trim(dir) // '/f_staged.h5', exist=there)
  call check(there, 'the file at its path after the commit')
  call cup_h5run_close(w, iclose)
  call check_int(iclose, CUP_OK, 'closed')
  call cup_h5run_begin(w, trim(dir) // '/no/such/dir/f.h5', 3, ierr, msg)
  call check(ierr < 0, 'a folder that does not exist is refused')
  call check(index(msg, 'no/such/dir') > 0, 'its words name the path: ' // trim(msg))
  call finish()
end program test_f_h5run
