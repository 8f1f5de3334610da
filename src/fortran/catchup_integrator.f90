! catchup_integrator -- Fortran wrappers of integrator.h: schedules, options,
! the run (conventions in catchup_base). Steps are numbered as in C,
! k = 0..n.
module catchup_integrator
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_double, c_char, c_ptr, c_funptr, &
    c_null_ptr, c_null_funptr, c_f_pointer, c_loc, c_funloc, c_int8_t, c_associated
  use catchup_constants
  use catchup_types
  use catchup_c
  use catchup_base
  implicit none
  private

  public :: cup_schedule_parse, cup_schedule_value, cup_schedule_format, &
    cup_integrator_options_default, cup_integrator_create, cup_integrator_create_process, &
    cup_integrator_free, &
    cup_integrator_run, cup_integrator_run_store, cup_integrator_state, cup_integrator_zeta, &
    cup_integrator_checkpoint_size, cup_integrator_checkpoint_save, cup_integrator_checkpoint_restore, &
    cup_integrator_resume, &
    cup_scheme_name, cup_scheme_parse, cup_output_name, cup_output_parse, cup_run_info_message
  ! for the other modules of the binding (not part of the documented API)
  public :: cup_expected_samples_, cup_options_or_default_

  !> value(n) = coef * n^power, for a default-kind or a c_long n
  interface cup_schedule_value
    module procedure schedule_value_int, schedule_value_long
  end interface cup_schedule_value

  !> What cup_integrator_run_store's sink fills (grown by doubling).
  type :: store_t
    integer :: dim = 0
    integer :: count = 0
    integer(c_long) :: last_k = -1
    logical :: nomem = .false.
    real(c_double), allocatable :: t(:)
    real(c_double), allocatable :: X(:, :)
  end type store_t

contains

  ! ---- integrator.h ------------------------------------------------------------------

  !> Parse "n^-2.1", "3e-7", "0.5*n^-1"; CUP_ERR_PARSE with a message otherwise.
  subroutine cup_schedule_parse(spec, s, ierr, errmsg)
    character(len=*), intent(in) :: spec
    type(cup_schedule), intent(out) :: s
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    cmsg = cup_errbuf_()
    st = c_cup_schedule_parse(cup_f_c_string(spec), s, cmsg)
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_schedule_parse

  real(c_double) function schedule_value_int(s, n)
    type(cup_schedule), intent(in) :: s
    integer, intent(in) :: n
    schedule_value_int = c_cup_schedule_value(s, int(n, c_long))
  end function schedule_value_int

  real(c_double) function schedule_value_long(s, n)
    type(cup_schedule), intent(in) :: s
    integer(c_long), intent(in) :: n
    schedule_value_long = c_cup_schedule_value(s, n)
  end function schedule_value_long

  !> The canonical text of a schedule ("n^-2.1", "1e-06", "0.5*n^-1.05").
  function cup_schedule_format(s) result(text)
    type(cup_schedule), intent(in) :: s
    character(len=:), allocatable :: text
    character(kind=c_char) :: probe(1)
    character(kind=c_char), allocatable :: buf(:)
    integer(c_int) :: n
    n = c_cup_schedule_format(s, probe, 1_c_long)
    allocate(buf(max(n, 0) + 1))
    n = c_cup_schedule_format(s, buf, int(size(buf), c_long))
    text = cup_chars_to_string(buf)
  end function cup_schedule_format

  !> The library's defaults (from the C function).
  subroutine cup_integrator_options_default(o)
    type(cup_integrator_options), intent(out) :: o
    call c_cup_integrator_options_default(o)
  end subroutine cup_integrator_options_default

  !> opt, or the library's defaults where it is absent (for the modules
  !> that create integrators).
  function cup_options_or_default_(opt) result(o)
    type(cup_integrator_options), intent(in), optional :: opt
    type(cup_integrator_options) :: o
    if (present(opt)) then
      o = opt
    else
      call c_cup_integrator_options_default(o)
    end if
  end function cup_options_or_default_

  !> An integrator for the LCS L with input u (absent: no input). L and u
  !> must outlive it; opt defaults to the library's.
  subroutine cup_integrator_create(integ, L, ierr, u, opt, errmsg)
    type(cup_integrator_t), intent(out) :: integ
    type(cup_lcs_t), intent(in) :: L
    integer, intent(out) :: ierr
    type(cup_input_t), intent(in), optional :: u
    type(cup_integrator_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_integrator_options) :: o
    type(c_ptr) :: up
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(L%ptr, 'integrator: LCS', ierr, errmsg)) return
    o = cup_options_or_default_(opt)
    up = c_null_ptr
    if (present(u)) up = u%ptr
    cmsg = cup_errbuf_()
    st = c_cup_integrator_create(integ%ptr, L%ptr, up, o, cmsg)
    if (st == CUP_OK) then
      integ%dim = int(c_cup_lcs_dim(L%ptr))
      integ%rows = int(c_cup_lcs_rows(L%ptr))
      integ%expected = cup_expected_samples_(o)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_integrator_create

  !> A general sweeping process x' in -N(S(t); x) + f(t, x) on the set S,
  !> f = A x + E u(t) + f(t, x) (c_funloc of a procedure(cup_rhs_fn), with
  !> f_ctx) + a term given by its exact integral (procedure(cup_rhs_integral_fn)).
  !> A (n x n) and E (n x p) are dense and optional; u moves the set (its p
  !> parameters) and drives E. S and u must outlive integ.
  subroutine cup_integrator_create_process(integ, S, ierr, u, A, E, f, f_ctx, f_integral, &
                                           f_integral_ctx, opt, errmsg)
    type(cup_integrator_t), intent(out) :: integ
    type(cup_set_t), intent(in) :: S
    integer, intent(out) :: ierr
    type(cup_input_t), intent(in), optional :: u
    real(c_double), intent(in), optional :: A(:, :), E(:, :)
    ! not VALUE: gfortran 12 reads an absent OPTIONAL VALUE of derived type; a
    ! c_funloc(...) actual may then become a constant in the caller's image
    type(c_funptr), intent(in), optional :: f, f_integral
    type(c_ptr), intent(in), optional :: f_ctx, f_integral_ctx
    type(cup_integrator_options), intent(in), optional :: opt
    character(len=*), intent(out), optional :: errmsg
    type(cup_process_desc) :: d
    type(cup_integrator_options) :: o
    type(cup_csc_matrix), target :: cA, cE
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    integer(c_int) :: st
    if (cup_null_fail_(S%ptr, 'integrator: set', ierr, errmsg)) return
    o = cup_options_or_default_(opt)
    d%n = int(S%dim, c_int)
    d%C = S%ptr
    if (present(u)) then
      d%u = u%ptr
      d%p = c_cup_input_dim(u%ptr)
    end if
    if (present(A)) then
      call cup_csc_from_dense(A, cA, ierr)
      d%A = cup_csc_view(cA)
    end if
    if (present(E)) then
      call cup_csc_from_dense(E, cE, ierr)
      d%E = cup_csc_view(cE)
    end if
    if (present(f)) d%f = f
    if (present(f_ctx)) d%f_ctx = f_ctx
    if (present(f_integral)) d%f_integral = f_integral
    if (present(f_integral_ctx)) d%f_integral_ctx = f_integral_ctx
    cmsg = cup_errbuf_()
    st = c_cup_integrator_create_process(integ%ptr, d, o, cmsg)
    if (st == CUP_OK) then
      integ%dim = S%dim
      integ%rows = int(c_cup_integrator_rows(integ%ptr))   ! a polyset's rows; 0 for another set
      integ%expected = cup_expected_samples_(o)
    end if
    call cup_finish_(st, cmsg, ierr, errmsg)
  end subroutine cup_integrator_create_process

  !> Samples a complete run passes to the sink (integrator.h, output kinds).
  pure integer(c_long) function cup_expected_samples_(o) result(ns)
    type(cup_integrator_options), intent(in) :: o
    select case (o%output)
    case (CUP_OUTPUT_EVERY)
      ns = o%n / o%output_every + 1
      if (mod(o%n, o%output_every) /= 0) ns = ns + 1
    case (CUP_OUTPUT_SAMPLES)
      ns = o%output_samples
    case (CUP_OUTPUT_FINAL)
      ns = 1
    case default
      ns = 0
    end select
  end function cup_expected_samples_

  subroutine cup_integrator_free(integ)
    type(cup_integrator_t), intent(inout) :: integ
    call c_cup_integrator_free(integ%ptr)
    integ%ptr = c_null_ptr
    integ%dim = 0
    integ%rows = 0
    integ%expected = 0
  end subroutine cup_integrator_free

  !> Run from x0 (dim entries) over [0, T], passing the selected states to
  !> sink = c_funloc(f) of a bind(C) procedure(cup_sample_fn) with sink_ctx
  !> (c_null_funptr: no sink). ierr = info%status: CUP_OK, a warning, or the
  !> error that stopped the run (info%step, info%t and info%message say where;
  !> errmsg gets the message).
  subroutine cup_integrator_run(integ, x0, sink, sink_ctx, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: x0(:)
    type(c_funptr), value :: sink
    type(c_ptr), value :: sink_ctx
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    type(cup_run_info) :: ri
    if (cup_null_fail_(integ%ptr, 'integrator', ierr, errmsg)) return
    if (size(x0) /= integ%dim) then
      call cup_size_fail_('x0', size(x0), integ%dim, ierr, errmsg)
      return
    end if
    ierr = int(c_cup_integrator_run(integ%ptr, x0, sink, sink_ctx, ri))
    if (present(info)) info = ri
    if (present(errmsg)) errmsg = cup_chars_to_string(ri%message)
  end subroutine cup_integrator_run

  !> Run from x0 and return the selected samples column-major: t(nsamples),
  !> X(dim, nsamples). On an error the samples before it are kept.
  subroutine cup_integrator_run_store(integ, x0, t, X, nsamples, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(in) :: x0(:)
    real(c_double), allocatable, intent(out) :: t(:)
    real(c_double), allocatable, intent(out) :: X(:, :)
    integer, intent(out) :: nsamples
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    type(store_t), target :: s
    type(cup_run_info) :: ri
    integer :: cap, ist
    nsamples = 0
    allocate(t(0), X(max(integ%dim, 0), 0))
    if (cup_null_fail_(integ%ptr, 'integrator', ierr, errmsg)) return
    if (size(x0) /= integ%dim) then
      call cup_size_fail_('x0', size(x0), integ%dim, ierr, errmsg)
      return
    end if
    s%dim = integ%dim
    cap = int(min(max(integ%expected, 1_c_long), int(huge(cap), c_long)))
    allocate(s%t(cap), s%X(s%dim, cap), stat=ist)
    if (ist /= 0) then                  ! too large at once: let it grow instead
      cap = 1024
      allocate(s%t(cap), s%X(s%dim, cap))
    end if
    ierr = int(c_cup_integrator_run(integ%ptr, x0, c_funloc(store_sink), c_loc(s), ri))
    if (s%nomem) then
      ierr = CUP_ERR_NOMEM
      ri%status = CUP_ERR_NOMEM
      call set_message(ri, 'out of memory storing the trajectory in Fortran arrays')
    end if
    nsamples = s%count
    deallocate(t, X)
    if (size(s%t) == nsamples) then
      call move_alloc(s%t, t)
      call move_alloc(s%X, X)
    else
      allocate(t(nsamples), X(s%dim, nsamples))
      t = s%t(1:nsamples)
      X = s%X(:, 1:nsamples)
    end if
    if (present(info)) info = ri
    if (present(errmsg)) errmsg = cup_chars_to_string(ri%message)
  end subroutine cup_integrator_run_store

  subroutine set_message(ri, text)
    type(cup_run_info), intent(inout) :: ri
    character(len=*), intent(in) :: text
    integer :: i, n
    n = min(len(text), size(ri%message) - 1)
    do i = 1, n
      ri%message(i) = text(i:i)
    end do
    ri%message(n + 1:) = char(0)
  end subroutine set_message

  !> The sink of cup_integrator_run_store: append (t, x) to the store_t at ctx.
  function store_sink(k, t, x, ctx) result(stat) bind(C)
    integer(c_long), value :: k
    real(c_double), value :: t
    real(c_double), intent(in) :: x(*)
    type(c_ptr), value :: ctx
    integer(c_int) :: stat
    type(store_t), pointer :: s
    real(c_double), allocatable :: t2(:), X2(:, :)
    integer :: cap, ist
    call c_f_pointer(ctx, s)
    if (s%count == size(s%t)) then
      cap = max(2 * size(s%t), 16)
      allocate(t2(cap), X2(s%dim, cap), stat=ist)
      if (ist /= 0) then
        s%nomem = .true.
        stat = 1
        return
      end if
      t2(1:s%count) = s%t(1:s%count)
      X2(:, 1:s%count) = s%X(:, 1:s%count)
      call move_alloc(t2, s%t)
      call move_alloc(X2, s%X)
    end if
    s%count = s%count + 1
    s%last_k = k
    s%t(s%count) = t
    s%X(:, s%count) = x(1:s%dim)
    stat = 0
  end function store_sink

  !> Copy the final state of the last run (dim entries) into x.
  subroutine cup_integrator_state(integ, x, ierr)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(inout) :: x(:)
    integer, intent(out) :: ierr
    logical :: found
    if (cup_null_fail_(integ%ptr, 'integrator', ierr)) return
    if (size(x) /= integ%dim) then
      call cup_size_fail_('x', size(x), integ%dim, ierr)
      return
    end if
    call cup_copy_out_(c_cup_integrator_state(integ%ptr), integ%dim, x, found, ierr)
  end subroutine cup_integrator_state

  !> Bytes of the checkpoint of the last run's stop (a stop at a step's end:
  !> the interrupt flag, the sink, the step callback, the time limit), or a
  !> negative status when there is none to save.
  function cup_integrator_checkpoint_size(integ) result(n)
    type(cup_integrator_t), intent(in) :: integ
    integer(c_long) :: n
    n = CUP_ERR_ARG
    if (c_associated(integ%ptr)) n = c_cup_integrator_checkpoint_size(integ%ptr)
  end function cup_integrator_checkpoint_size

  !> The stopped run (info: what it returned) as a byte blob, allocated here.
  subroutine cup_integrator_checkpoint_save(integ, info, blob, ierr)
    type(cup_integrator_t), intent(in) :: integ
    type(cup_run_info), intent(in) :: info
    integer(c_int8_t), allocatable, target, intent(out) :: blob(:)
    integer, intent(out) :: ierr
    integer(c_long) :: n
    n = cup_integrator_checkpoint_size(integ)
    if (n < 0) then
      ierr = int(n)
      return
    end if
    allocate(blob(max(n, 1_c_long)))
    ierr = int(c_cup_integrator_checkpoint_save(integ%ptr, info, c_loc(blob), n))
  end subroutine cup_integrator_checkpoint_save

  !> Read a blob into an integrator made as the saved one was (errmsg: why not).
  subroutine cup_integrator_checkpoint_restore(integ, blob, ierr, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    integer(c_int8_t), target, intent(in) :: blob(:)
    integer, intent(out) :: ierr
    character(len=*), intent(out), optional :: errmsg
    character(kind=c_char) :: cmsg(CUP_ERRMSG_LEN)
    if (cup_null_fail_(integ%ptr, 'integrator', ierr, errmsg)) return
    cmsg = cup_errbuf_()
    ierr = int(c_cup_integrator_checkpoint_restore(integ%ptr, c_loc(blob), int(size(blob), c_long), cmsg))
    if (present(errmsg)) errmsg = cup_chars_to_string(cmsg)
  end subroutine cup_integrator_checkpoint_restore

  !> Continue a restored run to T, as cup_integrator_run would have (the same
  !> steps bit for bit); info continues the saved run's statistics.
  subroutine cup_integrator_resume(integ, sink, sink_ctx, ierr, info, errmsg)
    type(cup_integrator_t), intent(in) :: integ
    type(c_funptr), value :: sink
    type(c_ptr), value :: sink_ctx
    integer, intent(out) :: ierr
    type(cup_run_info), intent(out), optional :: info
    character(len=*), intent(out), optional :: errmsg
    type(cup_run_info) :: ri
    if (cup_null_fail_(integ%ptr, 'integrator', ierr, errmsg)) return
    ierr = int(c_cup_integrator_resume(integ%ptr, sink, sink_ctx, ri))
    if (present(info)) info = ri
    if (present(errmsg)) errmsg = cup_chars_to_string(ri%message)
  end subroutine cup_integrator_resume

  !> zeta of the last step (rows entries): the diodes' currents and reverse
  !> voltages of a netlist, for cup_netlist_signals (before the first step, at
  !> t = 0: as the C function says, cup_integrator_zeta in catchup/integrator.h).
  !> A process on a polyset has one per row of its set (rows); a process on
  !> another set has none (rows = 0, ierr = CUP_ERR_UNSUPPORTED).
  subroutine cup_integrator_zeta(integ, zeta, ierr)
    type(cup_integrator_t), intent(in) :: integ
    real(c_double), intent(out) :: zeta(:)
    integer, intent(out) :: ierr
    real(c_double) :: buf(integ%rows + 1)
    if (cup_null_fail_(integ%ptr, 'integrator', ierr)) return
    if (size(zeta) /= integ%rows) then
      call cup_size_fail_('zeta', size(zeta), integ%rows, ierr)
      return
    end if
    ierr = int(c_cup_integrator_zeta(integ%ptr, buf))
    zeta = buf(1:integ%rows)
  end subroutine cup_integrator_zeta

  function cup_scheme_name(scheme) result(s)
    integer, intent(in) :: scheme
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_scheme_name(int(scheme, c_int)))
  end function cup_scheme_name

  !> A name of CUP_SCHEME_LIST ("explicit", "implicit", "exponential", "theta") -> CUP_SCHEME_*;
  !> -1 if unknown.
  integer function cup_scheme_parse(name)
    character(len=*), intent(in) :: name
    cup_scheme_parse = int(c_cup_scheme_parse(cup_f_c_string(name)))
  end function cup_scheme_parse

  function cup_output_name(output) result(s)
    integer, intent(in) :: output
    character(len=:), allocatable :: s
    s = cup_c_string(c_cup_output_name(int(output, c_int)))
  end function cup_output_name

  !> "every", "samples", "final", "none", "tol" -> CUP_OUTPUT_*; -1 if unknown.
  integer function cup_output_parse(name)
    character(len=*), intent(in) :: name
    cup_output_parse = int(c_cup_output_parse(cup_f_c_string(name)))
  end function cup_output_parse

  !> info%message as a Fortran string.
  function cup_run_info_message(info) result(s)
    type(cup_run_info), intent(in) :: info
    character(len=:), allocatable :: s
    s = cup_chars_to_string(info%message)
  end function cup_run_info_message
end module catchup_integrator
