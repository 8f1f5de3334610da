! catchup_crowd -- crowd.h in Fortran: Maury and Venel's crowd (a room,
! doors, obstacles, agents walking to the doors without overlapping) as a
! state-dependent sweeping process. Raw bind(C) interfaces c_cup_crowd_*,
! the descriptor cup_crowd_desc, then wrappers (conventions in
! catchup_base). Points are columns of 2 x N arrays (x in row 1, y in
! row 2); agents, doors and obstacles are numbered from 0 in the C
! messages, as C counts.
module catchup_crowd
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_char, c_ptr, c_null_ptr, c_loc, &
    c_associated, c_f_pointer
  use catchup_constants
  use catchup_types
  use catchup_base
  use catchup_c, only: c_cup_integrator_create_process, c_cup_integrator_rows
  use catchup_integrator, only: cup_expected_samples_, cup_options_or_default_
  implicit none
  private

  !> What a crowd is (cup_crowd_desc); pointers to the caller's arrays.
  type, bind(C), public :: cup_crowd_desc
    integer(c_int) :: agents = 0
    type(c_ptr) :: q0 = c_null_ptr
    type(c_ptr) :: radius = c_null_ptr
    integer(c_int) :: room_points = 0
    type(c_ptr) :: room = c_null_ptr
    integer(c_int) :: doors = 0
    type(c_ptr) :: door = c_null_ptr
    integer(c_int) :: obstacles = 0
    type(c_ptr) :: obstacle_points = c_null_ptr
    type(c_ptr) :: obstacle = c_null_ptr
    integer(c_int) :: walls = 0
    type(c_ptr) :: wall = c_null_ptr
    real(c_double) :: speed = 1
    real(c_double) :: grid = 0
    real(c_double) :: margin = 0
    real(c_double) :: reach = 0
    real(c_double) :: clearance = 0
  end type cup_crowd_desc

  !> A crowd (C: cup_crowd *).
  type, public :: cup_crowd_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: agents = 0
  end type cup_crowd_t

  public :: c_cup_crowd_create, c_cup_crowd_free, c_cup_crowd_agents, c_cup_crowd_q0, &
    c_cup_crowd_radii, c_cup_crowd_process, c_cup_crowd_exit_times, c_cup_crowd_inside, &
    c_cup_crowd_gap, c_cup_crowd_rows, c_cup_crowd_added, c_cup_crowd_door_distance, &
    c_cup_crowd_desired_velocity, c_cup_crowd_walls, c_cup_crowd_min_gap, c_cup_crowd_warning
  public :: cup_crowd_create, cup_crowd_free, cup_crowd_integrator, cup_crowd_exit_times, &
    cup_crowd_inside, cup_crowd_door_distance, cup_crowd_min_gap, cup_crowd_warning

  ! The raw bind(C) interfaces c_<C name>, generated from the header at build time (gen_bindings.py)
  include "bind_crowd.inc"

contains

  !> A crowd: q0 and room are 2 x N and 2 x V arrays of points, radius N
  !> radii, doors 4 x D (x0, y0, x1, y1), walls 4 x W; h is the time step
  !> T / n of the run (for the default margin).
  subroutine cup_crowd_create(c, q0, radius, room, doors, speed, h, ierr, walls, grid, errmsg, clearance)
    type(cup_crowd_t), intent(out) :: c
    real(c_double), intent(in), target, contiguous :: q0(:, :), radius(:), room(:, :), doors(:, :)
    real(c_double), intent(in) :: speed, h
    integer, intent(out) :: ierr
    real(c_double), intent(in), target, contiguous, optional :: walls(:, :)
    real(c_double), intent(in), optional :: grid
    character(len=*), intent(out), optional :: errmsg
    real(c_double), intent(in), optional :: clearance
    type(cup_crowd_desc) :: d
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (size(q0, 1) /= 2 .or. size(room, 1) /= 2 .or. size(doors, 1) /= 4 .or. &
        size(radius) /= size(q0, 2)) then
      call cup_fail_(int(CUP_ERR_DIM, c_int), 'crowd: q0 must be 2 x N, radius N, room 2 x V, doors 4 x D', ierr, errmsg)
      return
    end if
    d%agents = int(size(radius), c_int)
    d%q0 = c_loc(q0)
    d%radius = c_loc(radius)
    d%room_points = int(size(room, 2), c_int)
    d%room = c_loc(room)
    d%doors = int(size(doors, 2), c_int)
    d%door = c_loc(doors)
    d%speed = speed
    if (present(walls)) then
      d%walls = int(size(walls, 2), c_int)
      d%wall = c_loc(walls)
    end if
    if (present(grid)) d%grid = grid
    if (present(clearance)) d%clearance = clearance
    cmsg = cup_errbuf_()
    st = c_cup_crowd_create(c%ptr, d, h, cmsg)
    if (st == CUP_OK) c%agents = size(radius)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_crowd_create

  subroutine cup_crowd_free(c)
    type(cup_crowd_t), intent(inout) :: c
    call c_cup_crowd_free(c%ptr)
    c%agents = 0
  end subroutine cup_crowd_free

  !> An integrator of the crowd's process (state: the 2N coordinates).
  subroutine cup_crowd_integrator(c, integ, ierr, opt, errmsg)
    type(cup_crowd_t), intent(in) :: c
    type(cup_integrator_t), intent(out) :: integ
    integer, intent(out) :: ierr
    type(cup_integrator_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_process_desc), pointer :: d
    type(cup_integrator_options) :: o
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(c%ptr, 'crowd', ierr, errmsg)) return
    o = cup_options_or_default_(opt)
    call c_f_pointer(c_cup_crowd_process(c%ptr), d)
    cmsg = cup_errbuf_()
    st = c_cup_integrator_create_process(integ%ptr, d, o, cmsg)
    if (st == CUP_OK) then
      integ%dim = 2 * c%agents
      integ%rows = int(c_cup_integrator_rows(integ%ptr))
      integ%expected = cup_expected_samples_(o)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_crowd_integrator

  !> The agents' exit times (NaN while inside), a copy.
  function cup_crowd_exit_times(c) result(t)
    type(cup_crowd_t), intent(in) :: c
    real(c_double), allocatable :: t(:)
    real(c_double), pointer :: p(:)
    allocate(t(c%agents))
    if (c%agents == 0) return
    call c_f_pointer(c_cup_crowd_exit_times(c%ptr), p, [c%agents])
    t = p
  end function cup_crowd_exit_times

  !> What the creation allows but warns of (a door narrower than the
  !> smallest agent), or '' when nothing.
  function cup_crowd_warning(c) result(s)
    type(cup_crowd_t), intent(in) :: c
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_crowd_warning(c%ptr))
  end function cup_crowd_warning

  integer function cup_crowd_inside(c)
    type(cup_crowd_t), intent(in) :: c
    cup_crowd_inside = int(c_cup_crowd_inside(c%ptr))
  end function cup_crowd_inside

  real(c_double) function cup_crowd_door_distance(c, x, y)
    type(cup_crowd_t), intent(in) :: c
    real(c_double), intent(in) :: x, y
    cup_crowd_door_distance = c_cup_crowd_door_distance(c%ptr, x, y)
  end function cup_crowd_door_distance

  !> The smallest gap of the state q (2N entries, or 2 x N).
  real(c_double) function cup_crowd_min_gap(c, q)
    type(cup_crowd_t), intent(in) :: c
    real(c_double), intent(in), contiguous :: q(:)
    cup_crowd_min_gap = c_cup_crowd_min_gap(c%ptr, q)
  end function cup_crowd_min_gap
end module catchup_crowd
