/* catchup.h — the one public header of the catchup library.
 *
 * catchup simulates Moreau sweeping processes and linear complementarity
 * systems by the inexact catching-up algorithm. Conventions (docs/design.md):
 * prefix cup_; create / set / solve / free; options structs filled by
 * cup_*_options_default(); 0 ok, negative errors, positive warnings; the
 * library never prints, exits or aborts. */
#ifndef CATCHUP_H
#define CATCHUP_H

#include "catchup/version.h"
#include "catchup/status.h"
#include "catchup/sparse.h"
#include "catchup/polyset.h"
#include "catchup/projection.h"
#include "catchup/projector.h"
#include "catchup/set.h"
#include "catchup/input.h"
#include "catchup/lcs.h"
#include "catchup/integrator.h"
#include "catchup/pss.h"
#include "catchup/crowd.h"
#include "catchup/scene.h"
#include "catchup/netlist.h"

#endif
