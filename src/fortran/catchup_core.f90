! catchup_core -- every wrapper of polyset.h, projector.h, set.h, input.h,
! lcs.h and integrator.h in one module (what `catchup` re-exports), gathered
! from the modules by layer: catchup_projector (the polyset and its
! projection), catchup_sets (moving sets, their projections, the rows of a
! state-dependent polyset), catchup_model (the input and the LCS),
! catchup_integrator (time stepping), catchup_crowd (crowds).
! Conventions in catchup_base.
module catchup_core
  use catchup_projector
  use catchup_sets
  use catchup_model
  use catchup_integrator
  use catchup_crowd
  implicit none
  public
end module catchup_core
