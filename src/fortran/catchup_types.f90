! catchup_types -- the C structs of the catchup API mirrored as bind(C)
! derived types (same members, same order, same C types: the layout test
! tests/fortran/test_layout compares every offset with the C compiler's),
! the opaque handles, and the callback interfaces.
!
! Mirrored structs carry zero/null default initialization so that a fresh
! variable is well defined; the *library defaults* of an options struct come
! only from the C functions cup_projector_options_default and
! cup_integrator_options_default (never copied here).
!
! One rename: C's cup_lcs_desc has both `p` (input dimension) and `P` (the
! metric); Fortran is case-insensitive, so the metric is `metric` here.
module catchup_types
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_long_long, c_double, &
    c_char, c_ptr, c_funptr, c_null_ptr, c_null_funptr, c_null_char
  use catchup_constants
  implicit none
  private

  ! ---- sparse.h -------------------------------------------------------------
  !> A 0-based CSC matrix *view* (cup_csc). The library copies what it needs.
  type, bind(C), public :: cup_csc
    integer(c_int) :: nrow = 0
    integer(c_int) :: ncol = 0
    type(c_ptr) :: colptr = c_null_ptr   !< ncol+1 column starts, colptr(0) = 0
    type(c_ptr) :: rowind = c_null_ptr   !< 0-based row indices
    type(c_ptr) :: values = c_null_ptr
  end type cup_csc

  !> A 0-based CSC matrix owned by Fortran (allocatable arrays), built by
  !> cup_csc_from_fortran / cup_csc_from_dense; cup_csc_view gives its view.
  type, public :: cup_csc_matrix
    integer(c_int) :: nrow = 0
    integer(c_int) :: ncol = 0
    integer(c_int), allocatable :: colptr(:)   !< 0-based, size ncol+1
    integer(c_int), allocatable :: rowind(:)   !< 0-based, size max(nnz, 1)
    real(c_double), allocatable :: values(:)   !< size max(nnz, 1)
  end type cup_csc_matrix

  ! ---- polyset.h ------------------------------------------------------------
  type, bind(C), public :: cup_metric
    integer(c_int) :: kind = CUP_METRIC_IDENTITY   !< cup_metric_kind
    type(c_ptr) :: diag = c_null_ptr               !< DIAGONAL: dim entries
    type(cup_csc) :: matrix                        !< SPARSE
    integer(c_int) :: lower_only = 0
  end type cup_metric

  ! ---- projector.h ----------------------------------------------------------
  type, bind(C), public :: cup_projector_options
    integer(c_int) :: method = 0           !< cup_proj_method
    real(c_double) :: eps_abs = 0
    real(c_double) :: eps_rel = 0
    real(c_double) :: eta_abs = 0
    real(c_double) :: eta_rel = 0
    integer(c_int) :: max_iter = 0
    integer(c_int) :: warm_start = 0
    integer(c_int) :: return_feasible = 0
    real(c_double) :: lipschitz = 0
    type(c_ptr) :: feasible_point = c_null_ptr   !< c_loc of dim entries (copied), or null
    integer(c_int) :: factor_updates = 0         !< 1: row updates of the sparse factor; 0: refactor
  end type cup_projector_options

  type, bind(C), public :: cup_proj_info
    integer(c_int) :: status = 0
    integer(c_int) :: method = 0
    integer(c_int) :: iterations = 0
    integer(c_int) :: factorizations = 0
    integer(c_int) :: skipped = 0
    integer(c_int) :: active = 0
    real(c_double) :: scale = 0
    real(c_double) :: eps_target = 0
    real(c_double) :: eta_target = 0
    real(c_double) :: eps_cert = 0
    real(c_double) :: eta_cert = 0
    real(c_double) :: violation = 0
    real(c_double) :: dual_value = 0
    real(c_double) :: farkas_gap = 0
    real(c_double) :: farkas_residual = 0
    integer(c_int) :: row_updates = 0
  end type cup_proj_info

  ! ---- input.h --------------------------------------------------------------
  type, bind(C), public :: cup_wave
    integer(c_int) :: kind = CUP_WAVE_CONSTANT   !< cup_wave_kind
    real(c_double) :: value = 0
    real(c_double) :: amplitude = 0
    real(c_double) :: frequency = 0
    real(c_double) :: phase = 0
    integer(c_int) :: npoints = 0
    type(c_ptr) :: t = c_null_ptr
    type(c_ptr) :: v = c_null_ptr
    ! SPICE sources (netlists): PULSE and DAMPED_SINE
    real(c_double) :: delay = 0         !< PULSE, DAMPED_SINE: start time
    real(c_double) :: damping = 0       !< DAMPED_SINE: decay rate after the delay
    real(c_double) :: value2 = 0        !< PULSE: the pulsed value
    real(c_double) :: rise = 0, fall = 0          !< PULSE: ramp times (0: a jump)
    real(c_double) :: width = 0, period = 0       !< PULSE: time at value2; period (0: once)
  end type cup_wave

  ! ---- lcs.h ----------------------------------------------------------------
  type, bind(C), public :: cup_lcs_desc
    integer(c_int) :: n = 0
    integer(c_int) :: m = 0
    integer(c_int) :: p = 0          !< input dimension
    type(cup_csc) :: A
    type(cup_csc) :: B
    type(cup_csc) :: C
    type(cup_csc) :: E
    type(c_ptr) :: F = c_null_ptr    !< m entries, or null for 0
    type(cup_csc) :: G
    type(cup_metric) :: metric       !< C's member `P` (renamed: Fortran is case-insensitive)
    real(c_double) :: pb_tol = 0
    ! D != 0 (netlist diodes whose current the state does not fix)
    type(cup_csc) :: D                   !< m x m; absent or zero: D = 0 (only theta runs D != 0)
    type(c_ptr) :: row_names = c_null_ptr   !< const char *const *: m names for messages, or null
    integer(c_int) :: keep_B = 0            !< 1: B kept as given, not checked against P B = C^T (theta only)
  end type cup_lcs_desc

  type, bind(C), public :: cup_circuit
    real(c_double) :: R1 = 0, R2 = 0, R3 = 0, L2 = 0, L3 = 0, C4 = 0
    real(c_double) :: G(2) = 0
  end type cup_circuit

  ! ---- integrator.h ---------------------------------------------------------
  type, bind(C), public :: cup_schedule
    real(c_double) :: coef = 0
    real(c_double) :: power = 0
  end type cup_schedule

  type, bind(C), public :: cup_integrator_options
    integer(c_int) :: scheme = 0           !< cup_scheme
    real(c_double) :: T = 0
    integer(c_long) :: n = 0
    type(cup_schedule) :: eps
    type(cup_schedule) :: eta
    type(cup_projector_options) :: proj
    integer(c_int) :: output = 0           !< cup_output_kind
    integer(c_long) :: output_every = 0
    integer(c_long) :: output_samples = 0
    type(c_funptr) :: f = c_null_funptr    !< c_funloc of a procedure(cup_rhs_fn), or null
    type(c_ptr) :: f_ctx = c_null_ptr
    integer(c_int) :: f_order = 0
    real(c_double) :: max_wall_seconds = 0
    real(c_double) :: theta = 0                  !< THETA scheme: in [0, 1]
    type(c_funptr) :: on_step = c_null_funptr   !< c_funloc of a procedure(cup_step_fn)
    type(c_ptr) :: step_ctx = c_null_ptr
    type(c_ptr) :: interrupt = c_null_ptr   !< c_loc of an integer(c_int) flag polled every 1024 steps
    ! the adaptive scheme and error estimates
    real(c_double) :: tol_abs = 0               !< ADAPTIVE: absolute error target on x (max norm)
    real(c_double) :: tol_rel = 0               !< ADAPTIVE: error target relative to max |x(t)|
    real(c_double) :: max_event_rate = 0        !< ADAPTIVE: events per unit time taken for Zeno; 0: 1e5 / T
    type(c_funptr) :: on_event = c_null_funptr  !< c_funloc of a procedure(cup_event_fn), or null
    type(c_ptr) :: event_ctx = c_null_ptr
    integer(c_int) :: estimate = 0              !< fixed-step schemes: 1 = step-doubling error estimate
    real(c_double) :: hmax = 0                  !< ADAPTIVE: no step longer than this (TMAX); 0: none
    real(c_double) :: output_t0 = 0             !< SAMPLES: the first sample's time (TSTART)
    real(c_double) :: output_tol = 0            !< TOL (adaptive): what lines between the points are within
  end type cup_integrator_options

  type, bind(C), public :: cup_run_info
    integer(c_int) :: status = 0
    integer(c_long) :: step = 0
    real(c_double) :: t = 0
    integer(c_long) :: projected = 0
    integer(c_long) :: skipped = 0
    integer(c_long) :: not_certified = 0
    integer(c_long_long) :: dual_iterations = 0
    integer(c_long) :: factorizations = 0
    real(c_double) :: max_eps_cert = 0
    real(c_double) :: max_eta_cert = 0
    real(c_double) :: eps_target = 0
    real(c_double) :: eta_target = 0
    real(c_double) :: h_rho = 0
    integer(c_long) :: samples = 0
    character(kind=c_char) :: message(CUP_RUN_MSG_LEN) = c_null_char   !< use cup_run_info_message(info)
    integer(c_long) :: set_rebuilds = 0   !< state polyset: symbolic analyses of the run
    integer(c_long) :: max_rows = 0       !< state polyset: the most rows of one step
    ! the adaptive scheme and error estimates
    real(c_double) :: err_est = 0      !< estimate of max_t |x(t) - x_exact(t)|_inf; NaN when not estimated
    integer(c_long) :: events = 0      !< ADAPTIVE: changes of the active set
    integer(c_long) :: rejected = 0    !< ADAPTIVE: steps rejected by the error test
  end type cup_run_info

  ! ---- set.h, and the process of integrator.h ---------------------------------
  !> A moving set (cup_set_desc): each field says in set.h which kinds read it.
  !> C's member `P` is `metric` here (Fortran is case-insensitive: `p` is the
  !> number of parameters).
  type, bind(C), public :: cup_set_desc
    integer(c_int) :: kind = CUP_SET_POLYSET   !< cup_set_kind
    integer(c_int) :: n = 0
    integer(c_int) :: p = 0                    !< parameters u that move the set
    type(cup_metric) :: metric
    type(cup_csc) :: C                         !< POLYSET, INTERSECTION: m x n; HALFSPACE: 1 x n
    type(c_ptr) :: F = c_null_ptr              !< m entries (HALFSPACE: b), or null for 0
    type(cup_csc) :: G                         !< m x p, the offset's motion
    type(c_ptr) :: center = c_null_ptr         !< n entries, or null for 0
    type(cup_csc) :: Gc                        !< n x p, the centre's motion
    real(c_double) :: radius = 0
    type(c_ptr) :: gr = c_null_ptr             !< p entries: r = radius + gr . u, or null
    type(cup_csc) :: Q                         !< ELLIPSOID: n x n SPD
    type(c_funptr) :: oracle = c_null_funptr   !< c_funloc of a procedure(cup_oracle_fn)
    type(c_ptr) :: oracle_ctx = c_null_ptr
    type(c_funptr) :: rows = c_null_funptr     !< c_funloc of a procedure(cup_rows_fn)
    type(c_ptr) :: rows_ctx = c_null_ptr
  end type cup_set_desc

  !> A general sweeping process (cup_process_desc); the set and u are borrowed.
  type, bind(C), public :: cup_process_desc
    integer(c_int) :: n = 0
    integer(c_int) :: p = 0
    type(c_ptr) :: C = c_null_ptr              !< the cup_set (cup_set_t%ptr)
    type(c_ptr) :: u = c_null_ptr              !< the cup_input (cup_input_t%ptr), or null
    type(cup_csc) :: A                         !< n x n, absent: no A x
    type(cup_csc) :: E                         !< n x p, absent: no E u
    type(c_funptr) :: f = c_null_funptr        !< c_funloc of a procedure(cup_rhs_fn), or null
    type(c_ptr) :: f_ctx = c_null_ptr
    type(c_funptr) :: f_integral = c_null_funptr   !< procedure(cup_rhs_integral_fn), or null
    type(c_ptr) :: f_integral_ctx = c_null_ptr
  end type cup_process_desc

  ! ---- handles --------------------------------------------------------------
  ! `ptr` is the C pointer (pass it to the raw interfaces of catchup_c);
  ! `borrowed` marks a handle the library owns (cup_lcs_polyset, cup_scene_*):
  ! freeing it only forgets the pointer. *_free sets ptr to c_null_ptr, so a
  ! second free is harmless.
  type, public :: cup_polyset_t
    type(c_ptr) :: ptr = c_null_ptr
    logical :: borrowed = .false.
  end type cup_polyset_t

  type, public :: cup_projector_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: dim = 0   !< variables of the polyset (cached at creation)
    integer :: m = 0     !< its constraints
  end type cup_projector_t

  type, public :: cup_input_t
    type(c_ptr) :: ptr = c_null_ptr
    logical :: borrowed = .false.
  end type cup_input_t

  type, public :: cup_lcs_t
    type(c_ptr) :: ptr = c_null_ptr
    logical :: borrowed = .false.
  end type cup_lcs_t

  type, public :: cup_integrator_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: dim = 0                 !< state dimension (cached at creation)
    integer :: rows = 0                !< complementarity rows m (cached at creation)
    integer(c_long) :: expected = 0    !< samples a full run passes to a sink
  end type cup_integrator_t

  type, public :: cup_set_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: dim = 0   !< n (cached at creation)
  end type cup_set_t

  type, public :: cup_setproj_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: dim = 0   !< n of its set
  end type cup_setproj_t

  type, public :: cup_scene_t
    type(c_ptr) :: ptr = c_null_ptr
  end type cup_scene_t

  type, public :: cup_netlist_t
    type(c_ptr) :: ptr = c_null_ptr
    logical :: borrowed = .false.
  end type cup_netlist_t

  type, public :: cup_h5run_t
    type(c_ptr) :: ptr = c_null_ptr
    integer :: dim = 0
  end type cup_h5run_t

  ! ---- callbacks (write them as bind(C) procedures, pass c_funloc(fn)) -------
  ! Their abstract interfaces, named and with dummies as the C typedefs
  ! (include/catchup/*.h say what each does), generated at build time
  ! (gen_bindings.py): procedure(cup_rhs_fn) :: my_f declares one.
  include "bind_callbacks.inc"
  public :: cup_input_fn, cup_rhs_fn, cup_sample_fn, cup_step_fn, cup_rhs_integral_fn, &
    cup_oracle_fn, cup_rows_fn, cup_event_fn
end module catchup_types
