/* options — a new integrator holding a checked copy of the options (the
 * defaults when opt is NULL); NULL with *st and errmsg set when they do not
 * hold or memory runs out. Internal to the library. */
#ifndef CUP_OPTIONS_H
#define CUP_OPTIONS_H

#include "catchup.h"

cup_integrator *integrator_new(const cup_integrator_options *opt, char *errmsg, int *st);
/* The same checks of options made inside (the estimate's run at n/2). */
int options_check(const cup_integrator_options *o, char *errmsg);

#endif
