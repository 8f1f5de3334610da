/* Internal layout of cup_input, and quadrature workspace owned by callers
 * (an input is read-only and may be shared; GSL workspaces are not). */
#ifndef CUP_INPUT_IMPL_H
#define CUP_INPUT_IMPL_H

#include <gsl/gsl_integration.h>
#include "catchup/input.h"

typedef struct cup_term {
  int comp;
  cup_wave_kind kind;
  double value, amp, omega, phase;  /* omega = 2 pi frequency */
  int np;
  double *t, *v;
  double delay, damping;                    /* PULSE, DAMPED_SINE */
  double value2, rise, fall, width, period; /* PULSE */
} cup_term;

struct cup_input {
  int p;
  int nterms;
  cup_term *terms;
  cup_input_fn fn;
  void *ctx;
  double abs_tol, rel_tol;
};

typedef struct cup_quad_ws {
  gsl_integration_workspace *w;
  size_t limit;
  double *buf;          /* p entries for the callback */
} cup_quad_ws;

/* The SPICE source functions (input_spice.c): PULSE and DAMPED_SINE. */
int cup_spice_term_init(cup_term *t, const cup_wave *w, char *errmsg);
double cup_spice_term_value(const cup_term *t, double tt);
double cup_spice_term_integral(const cup_term *t, double a, double b);
double cup_spice_term_break(const cup_term *t, double tt);   /* the next corner after tt, or INFINITY */
int cup_spice_term_constant(const cup_term *t);

/* One term's value at t (its component's share of u(t)). */
double cup_term_value(const cup_term *w, double t);
/* One term's exact integral over [a, b]. */
double cup_term_integral(const cup_term *w, double a, double b);

int cup_quad_ws_init(cup_quad_ws *ws, int p);
void cup_quad_ws_free(cup_quad_ws *ws);
/* Integral with a caller-owned workspace (needed only for callbacks). */
int cup_input_integral_ws(const cup_input *u, double a, double b, double *out,
                          cup_quad_ws *ws);

#endif
