! catchup_core -- every wrapper of polyset.h, projector.h, input.h, lcs.h and
! integrator.h in one module (what `catchup` re-exports), gathered from the
! modules by layer: catchup_projector (the set and its projection),
! catchup_model (the input and the LCS), catchup_integrator (time stepping).
! Conventions in catchup_base.
module catchup_core
  use catchup_projector
  use catchup_model
  use catchup_integrator
  implicit none
  public
end module catchup_core
