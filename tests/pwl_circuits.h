/* The example converters and rectifiers (examples/circuits) as switched
 * linear systems for tests/pwl_ref.h, each topology derived by hand from the
 * circuit's physics (which switches are closed, which diodes conduct): the
 * independent side of the tests and of scripts/bench-converters. The
 * element values are the netlists'; each builder names its netlist, and
 * the state x is in the netlist formulation's order (inductor currents,
 * then capacitor voltages, each in netlist order).
 *
 * Gates are PULSE(0 1 TD jump jump PW PER) sources; the exosystem holds
 * the constant 1 for DC sources, (sin w t, cos w t) for sines. */
#ifndef CUP_PWL_CIRCUITS_H
#define CUP_PWL_CIRCUITS_H

#include <stdarg.h>
#include "pwl_ref.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Row r of length ny from ny doubles. */
static inline void pc_row(double *r, int ny, ...) {
  va_list ap;
  va_start(ap, ny);
  for (int j = 0; j < ny; j++) r[j] = va_arg(ap, double);
  va_end(ap);
}

/* A new mode of gate configuration gate (-1: every one), with the
 * exosystem's rows: (sin, cos) at sin_at if >= 0 (a constant's row, 1' = 0,
 * stays zero). */
static inline pr_mode *pc_mode(pr_circuit *c, int gate, int sin_at, double w) {
  pr_mode *m = &c->mode[c->nmodes++];
  memset(m, 0, sizeof *m);
  m->gate = gate;
  if (sin_at >= 0) { m->M[sin_at][sin_at + 1] = w; m->M[sin_at + 1][sin_at] = -w; }
  return m;
}

/* The jump that zeroes the states listed (-1 ends the list): the energy
 * metric's projection onto {x_i = 0} when the metric is diagonal. */
static inline void pc_zero(pr_circuit *c, pr_mode *m, int i0, int i1) {
  m->jump = 1;
  for (int i = 0; i < c->ny; i++) m->J[i][i] = 1;
  if (i0 >= 0) m->J[i0][i0] = 0;
  if (i1 >= 0) m->J[i1][i1] = 0;
}

static inline void pc_gate(pr_circuit *c, double td, double pw, double per) {
  c->td[c->ngates] = td; c->pw[c->ngates] = pw; c->per[c->ngates] = per;
  c->ngates++;
}

/* The two-state converters below (buck, boost, buck-boost): y = (i(L1),
 * v(C1), 1), S1 gated at duty D. pc_converter sets the sizes and the gate
 * and returns the first mode, S1 on, for the caller's rows. */
static inline pr_mode *pc_converter(pr_circuit *c, double D, double Ts) {
  memset(c, 0, sizeof *c);
  c->n = 2; c->ny = 3; c->hsub = Ts / 20;
  pc_gate(c, 0, D * Ts, Ts);
  return pc_mode(c, 1, -1, 0);
}

/* Their discontinuous mode, S1 and D1 off: i = 0, C1 discharges into R,
 * while D1's reverse voltage g1 v + g2 stays >= 0. */
static inline void pc_converter_dcm(pr_circuit *c, double R, double C, double g1, double g2) {
  pr_mode *m = pc_mode(c, 0, -1, 0);
  pc_row(m->M[1], 3, 0.0, -1 / (R * C), 0.0);
  pc_zero(c, m, 0, -1);
  m->ng = 1; pc_row(m->g[0], 3, 0.0, g1, g2);
}

/* ---- buck.cir-like: Vin, S1 in-sw gated, D1 0->sw, L1 sw-out, C1 || RL ----
 * y = (i(L1), v(C1), 1). On: L i' = Vin - v. Off, D1 on: L i' = -v while
 * i >= 0. Off, D1 off: i = 0 while D1's reverse voltage v(sw) = v >= 0. */
static inline void pc_buck(pr_circuit *c, double Vin, double L, double C, double R, double D, double Ts) {
  pr_mode *m = pc_converter(c, D, Ts);
  pc_row(m->M[0], 3, 0.0, -1 / L, Vin / L);
  pc_row(m->M[1], 3, 1 / C, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 0.0, 0.0, Vin);             /* D1 reverse: v(sw) = Vin */
  m = pc_mode(c, 0, -1, 0);
  pc_row(m->M[0], 3, 0.0, -1 / L, 0.0);
  pc_row(m->M[1], 3, 1 / C, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 1.0, 0.0, 0.0);             /* D1's current i */
  pc_converter_dcm(c, R, C, 1.0, 0.0);                      /* D1 reverse: v(sw) = v */
}

/* ---- boost: Vin, L1 in-sw, S1 sw-0 gated, D1 sw->out, C1 || RL ----
 * On: L i' = Vin, D1 reverse v >= 0. Off, D1 on: L i' = Vin - v,
 * C v' = i - v/R while i >= 0. Off, D1 off: i = 0 while v - Vin >= 0. */
static inline void pc_boost(pr_circuit *c, double Vin, double L, double C, double R, double D, double Ts) {
  pr_mode *m = pc_converter(c, D, Ts);
  pc_row(m->M[0], 3, 0.0, 0.0, Vin / L);
  pc_row(m->M[1], 3, 0.0, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 0.0, 1.0, 0.0);
  m = pc_mode(c, 0, -1, 0);
  pc_row(m->M[0], 3, 0.0, -1 / L, Vin / L);
  pc_row(m->M[1], 3, 1 / C, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 1.0, 0.0, 0.0);
  pc_converter_dcm(c, R, C, 1.0, -Vin);
}

/* ---- inverting buck-boost: Vin, S1 in-sw gated, L1 sw-0, D1 out->sw,
 * C1 out-0 || RL (v < 0) ----
 * On: L i' = Vin, C v' = -v/R, D1 reverse Vin - v >= 0. Off, D1 on:
 * v(sw) = v, L i' = v, C v' = -i - v/R while i >= 0. Off, D1 off: i = 0
 * while D1's reverse voltage v(sw) - v = -v >= 0. */
static inline void pc_buckboost(pr_circuit *c, double Vin, double L, double C, double R, double D, double Ts) {
  pr_mode *m = pc_converter(c, D, Ts);
  pc_row(m->M[0], 3, 0.0, 0.0, Vin / L);
  pc_row(m->M[1], 3, 0.0, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 0.0, -1.0, Vin);
  m = pc_mode(c, 0, -1, 0);
  pc_row(m->M[0], 3, 0.0, 1 / L, 0.0);
  pc_row(m->M[1], 3, -1 / C, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 3, 1.0, 0.0, 0.0);
  pc_converter_dcm(c, R, C, -1.0, 0.0);
}

/* ---- flyback: Vin, L1 in-d (dot at in), S1 d-0 gated, L2 0-a (dot at 0),
 * K L1 L2 k, D1 a->out, C1 out-0 || RL ----
 * y = (i1, i2, v, 1); [L1 M; M L2] (i1', i2') = (v(in) - v(d), 0 - v(a)).
 * On, D1 on: (Vin, -v), C v' = i2 - v/R while i2 >= 0. On, D1 off: i2 = 0
 * (entered by the projection in the inductance metric onto i2 = 0, which
 * keeps the primary's flux L1 i1 + M i2), L1 i1' = Vin, while D1's reverse
 * voltage v - v(a) = v + (M/L1) Vin >= 0. Off, D1 on: i1 = 0 (the switch
 * opens the primary: the projection keeps the secondary's flux, i2 +=
 * (M/L2) i1, and the leakage's energy (1 - k^2) L1 i1^2 / 2 is lost),
 * L2 i2' = -v while i2 >= 0. Off, D1 off: i1 = i2 = 0 while v >= 0. */
static inline void pc_flyback(pr_circuit *c, double Vin, double L1, double L2, double k, double C, double R,
                              double D, double Ts) {
  memset(c, 0, sizeof *c);
  c->n = 3; c->ny = 4; c->hsub = Ts / 20;
  pc_gate(c, 0, D * Ts, Ts);
  double M = k * sqrt(L1 * L2), det = L1 * L2 - M * M;
  pr_mode *m = pc_mode(c, 1, -1, 0);                      /* on, D1 on */
  /* (i1', i2') = [L2 -M; -M L1] (Vin, -v) / det */
  pc_row(m->M[0], 4, 0.0, 0.0, M / det, L2 * Vin / det);
  pc_row(m->M[1], 4, 0.0, 0.0, -L1 / det, -M * Vin / det);
  pc_row(m->M[2], 4, 0.0, 1 / C, -1 / (R * C), 0.0);
  m->ng = 1; pc_row(m->g[0], 4, 0.0, 1.0, 0.0, 0.0);
  m = pc_mode(c, 1, -1, 0);                               /* on, D1 off */
  pc_row(m->M[0], 4, 0.0, 0.0, 0.0, Vin / L1);
  pc_row(m->M[2], 4, 0.0, 0.0, -1 / (R * C), 0.0);
  m->jump = 1;
  pc_row(m->J[0], 4, 1.0, M / L1, 0.0, 0.0);
  pc_row(m->J[2], 4, 0.0, 0.0, 1.0, 0.0);
  pc_row(m->J[3], 4, 0.0, 0.0, 0.0, 1.0);
  m->ng = 1; pc_row(m->g[0], 4, 0.0, 0.0, 1.0, M / L1 * Vin);
  m = pc_mode(c, 0, -1, 0);                               /* off, D1 on */
  pc_row(m->M[1], 4, 0.0, 0.0, -1 / L2, 0.0);
  pc_row(m->M[2], 4, 0.0, 1 / C, -1 / (R * C), 0.0);
  m->jump = 1;
  pc_row(m->J[1], 4, M / L2, 1.0, 0.0, 0.0);
  pc_row(m->J[2], 4, 0.0, 0.0, 1.0, 0.0);
  pc_row(m->J[3], 4, 0.0, 0.0, 0.0, 1.0);
  m->ng = 1; pc_row(m->g[0], 4, 0.0, 1.0, 0.0, 0.0);
  m = pc_mode(c, 0, -1, 0);                               /* off, D1 off */
  pc_row(m->M[2], 4, 0.0, 0.0, -1 / (R * C), 0.0);
  pc_zero(c, m, 0, 1);
  m->ng = 1; pc_row(m->g[0], 4, 0.0, 0.0, 1.0, 0.0);
}

/* ---- full bridge: Vdc; leg a: S1 dc-a (g1), S2 a-0 (g2), D1 a->dc, D2
 * 0->a; leg b: S3 dc-b (g3), S4 b-0 (g4), D3 b->dc, D4 0->b; L1 a-o,
 * C1 o-b || RL ----
 * y = (i, v, 1), i from a through L1 to o, v = v(o) - v(b);
 * L i' = v(a) - v(b) - v, C v' = i - v/R. A leg whose switch is closed
 * holds its node at Vdc or 0; in its dead time its diodes do: i > 0 leaves
 * a through the filter, so D2 conducts (v(a) = 0) and D3 returns it
 * (v(b) = Vdc); i < 0: D1 (v(a) = Vdc), D4 (v(b) = 0); i = 0: the dead
 * legs' diodes block (i stays 0) while each dead node's voltage, set by
 * the filter, stays within [0, Vdc]. Gates: bit 0..3 = g1..g4. */
static inline void pc_fullbridge(pr_circuit *c, double Vdc, double L, double C, double R, double Ts, double dead,
                                 double shift) {   /* shift < Ts / 2: leg b's lag */
  memset(c, 0, sizeof *c);
  c->n = 2; c->ny = 3; c->hsub = dead / 4;
  double half = Ts / 2, pw = half - dead;
  pc_gate(c, dead, pw, Ts);                      /* g1 */
  pc_gate(c, half + dead, pw, Ts);               /* g2 */
  pc_gate(c, shift + half + dead, pw, Ts);       /* g3 */
  pc_gate(c, shift + dead, pw, Ts);              /* g4: v(a) - v(b) = Vdc while S1 and S4 are on */
  for (int la = 0; la < 3; la++)                 /* 0: top on, 1: bottom on, 2: dead */
    for (int lb = 0; lb < 3; lb++) {
      int mask = (la == 0) | (la == 1) << 1 | (lb == 0) << 2 | (lb == 1) << 3;
      int dead_legs = (la == 2) + (lb == 2);
      static const int signs[3] = {1, -1, 0};   /* in a dead time: i >= 0, i <= 0, i = 0 */
      for (int q = 0; q < (dead_legs ? 3 : 1); q++) {
        int s = signs[q];
        /* v(a) - v(b) as an affine row: va = Vdc on top or (dead and i < 0) */
        double va = la == 0 ? Vdc : la == 1 ? 0 : (s < 0 ? Vdc : 0);
        double vb = lb == 0 ? Vdc : lb == 1 ? 0 : (s < 0 ? 0 : Vdc);
        pr_mode *m = pc_mode(c, mask, -1, 0);
        pc_row(m->M[1], 3, 1 / C, -1 / (R * C), 0.0);
        if (s != 0) {
          pc_row(m->M[0], 3, 0.0, -1 / L, (va - vb) / L);
          m->ng = dead_legs ? 1 : 0;
          pc_row(m->g[0], 3, (double)s, 0.0, 0.0);               /* the conducting diodes' current */
          continue;
        }
        pc_zero(c, m, 0, -1);                   /* i = 0: a dead node's voltage follows the filter */
        if (la == 2 && lb == 2) {                /* v(a) - v(b) = v, both in [0, Vdc] */
          m->ng = 2;
          pc_row(m->g[0], 3, 0.0, 1.0, Vdc);
          pc_row(m->g[1], 3, 0.0, -1.0, Vdc);
        } else if (la == 2) {                    /* v(a) = v(b) + v in [0, Vdc] */
          double vbk = lb == 0 ? Vdc : 0;
          m->ng = 2;
          pc_row(m->g[0], 3, 0.0, 1.0, vbk);
          pc_row(m->g[1], 3, 0.0, -1.0, Vdc - vbk);
        } else {                                 /* v(b) = v(a) - v in [0, Vdc] */
          double vak = la == 0 ? Vdc : 0;
          m->ng = 2;
          pc_row(m->g[0], 3, 0.0, -1.0, vak);
          pc_row(m->g[1], 3, 0.0, 1.0, Vdc - vak);
        }
      }
    }
}

/* ---- six-pulse rectifier: star sources va, vb, vc (peak Vp, phases 0,
 * -120, +120 degrees) from ground, D1 a->p, D3 b->p, D5 c->p, D4 n->a,
 * D6 n->b, D2 n->c, L1 p-out, C1 out-n || RL ----
 * y = (i, v, sin w t, cos w t). With i > 0 the highest phase j feeds p and
 * the lowest k returns from n: L i' = v_j - v_k - v while i >= 0 and
 * every other top diode's reverse voltage v_j - v_m >= 0, every other
 * bottom one's v_m - v_k >= 0. All off: i = 0 while v >= v_j - v_k for
 * every pair. */
static inline void pc_sixpulse(pr_circuit *c, double Vp, double f, double L, double C, double R) {
  memset(c, 0, sizeof *c);
  c->n = 2; c->ny = 4; c->hsub = 1 / (f * 720);
  double w = 2 * M_PI * f, ph[3][2];             /* v_j = Vp (ph[j][0] sin + ph[j][1] cos) */
  for (int j = 0; j < 3; j++) {
    double th = -2 * M_PI / 3 * (j == 1) + 2 * M_PI / 3 * (j == 2);   /* sin(w t + th) */
    ph[j][0] = Vp * cos(th);
    ph[j][1] = Vp * sin(th);
  }
  for (int j = 0; j < 3; j++)
    for (int k = 0; k < 3; k++) {
      if (j == k) continue;
      pr_mode *m = pc_mode(c, -1, 2, w);
      pc_row(m->M[0], 4, 0.0, -1 / L, (ph[j][0] - ph[k][0]) / L, (ph[j][1] - ph[k][1]) / L);
      pc_row(m->M[1], 4, 1 / C, -1 / (R * C), 0.0, 0.0);
      m->ng = 1;
      pc_row(m->g[0], 4, 1.0, 0.0, 0.0, 0.0);
      for (int q = 0; q < 3; q++) {
        if (q != j) pc_row(m->g[m->ng++], 4, 0.0, 0.0, ph[j][0] - ph[q][0], ph[j][1] - ph[q][1]);
        if (q != k) pc_row(m->g[m->ng++], 4, 0.0, 0.0, ph[q][0] - ph[k][0], ph[q][1] - ph[k][1]);
      }
    }
  pr_mode *m = pc_mode(c, -1, 2, w);
  pc_row(m->M[1], 4, 0.0, -1 / (R * C), 0.0, 0.0);
  pc_zero(c, m, 0, -1);
  for (int j = 0; j < 3; j++)
    for (int k = 0; k < 3; k++)
      if (j != k) pc_row(m->g[m->ng++], 4, 0.0, 1.0, ph[k][0] - ph[j][0], ph[k][1] - ph[j][1]);
}

/* ---- inverting half-wave precision rectifier: vin = Vp sin w t; R1
 * in-inm, R2 inm-vo, E1 oa 0 0 inm A, D1 inm->oa, D2 oa->vo, Rf vo-out,
 * Cf out-0 || RL ----
 * y = (v(out), sin, cos). The E's input draws nothing.
 * D2 on, D1 off: v(vo) = v(oa) = -A v(inm) and KCL at inm give v(inm) =
 * R2 vin / (R1 + R2 + A R1), v(vo) = -kg vin, kg = A R2 / (R1 + R2 + A R1);
 * D2's current (vo - inm)/R2 + (vo - v)/Rf >= 0 and D1's reverse voltage
 * v(oa) - v(inm) >= 0. D1 on, D2 off: v(inm) = v(oa) = 0, v(vo) = v R2 /
 * (R2 + Rf); D1's current vin/R1 + v/(R2 + Rf) >= 0 and D2's reverse
 * voltage v(vo) >= 0. Both off: inm and vo from the resistors, v(oa) =
 * -A v(inm); the reverse voltages v(oa) - v(inm) and v(vo) - v(oa) >= 0. */
static inline void pc_precision(pr_circuit *c, double Vp, double f, double R1, double R2, double A, double Rf,
                                double C, double RL) {
  memset(c, 0, sizeof *c);
  c->n = 1; c->ny = 3; c->hsub = 1 / (f * 2000);
  double w = 2 * M_PI * f, den = R1 + R2 + A * R1, kg = A * R2 / den, kin = R2 / den;
  pr_mode *m = pc_mode(c, -1, 1, w);         /* D2 on, D1 off */
  pc_row(m->M[0], 3, -1 / (Rf * C) - 1 / (RL * C), -kg * Vp / (Rf * C), 0.0);
  m->ng = 2;
  pc_row(m->g[0], 3, -1 / Rf, (-kg - kin) * Vp / R2 - kg * Vp / Rf, 0.0);
  pc_row(m->g[1], 3, 0.0, (-kg - kin) * Vp, 0.0);
  m = pc_mode(c, -1, 1, w);                  /* D1 on, D2 off */
  pc_row(m->M[0], 3, -1 / ((R2 + Rf) * C) - 1 / (RL * C), 0.0, 0.0);
  m->ng = 2;
  pc_row(m->g[0], 3, 1 / (R2 + Rf), Vp / R1, 0.0);
  pc_row(m->g[1], 3, R2 / (R2 + Rf), 0.0, 0.0);
  /* both off: [G11 G12; G12 G22] (inm, vo) = (vin/R1, v/Rf) */
  double G11 = 1 / R1 + 1 / R2, G12 = -1 / R2, G22 = 1 / R2 + 1 / Rf, det = G11 * G22 - G12 * G12;
  double inm_v = -G12 / Rf / det, inm_s = G22 * Vp / R1 / det;      /* inm = inm_v v + inm_s sin */
  double vo_v = G11 / Rf / det, vo_s = -G12 * Vp / R1 / det;
  m = pc_mode(c, -1, 1, w);
  pc_row(m->M[0], 3, (vo_v - 1) / (Rf * C) - 1 / (RL * C), vo_s / (Rf * C), 0.0);
  m->ng = 2;
  pc_row(m->g[0], 3, -(A + 1) * inm_v, -(A + 1) * inm_s, 0.0);
  pc_row(m->g[1], 3, vo_v + A * inm_v, vo_s + A * inm_s, 0.0);
}

/* The example netlists' circuits (examples/circuits/NAME.cir, the values
 * written there): the system, y(0) and the netlist's TSTOP; 0, or -1 for
 * an unknown name. */
static inline int pc_example(const char *name, pr_circuit *c, double *y0, double *T) {
  memset(y0, 0, sizeof(double) * PR_Y);
  if (!strcmp(name, "buck-ccm")) { pc_buck(c, 12, 100e-6, 10e-6, 5, 0.5, 10e-6); y0[2] = 1; *T = 1e-3; }
  else if (!strcmp(name, "buck-dcm")) { pc_buck(c, 12, 10e-6, 10e-6, 20, 0.3, 10e-6); y0[2] = 1; *T = 1e-3; }
  else if (!strcmp(name, "boost")) { pc_boost(c, 5, 50e-6, 20e-6, 10, 0.5, 10e-6); y0[2] = 1; *T = 1e-3; }
  else if (!strcmp(name, "buckboost")) { pc_buckboost(c, 12, 50e-6, 20e-6, 10, 0.5, 10e-6); y0[2] = 1; *T = 1e-3; }
  else if (!strcmp(name, "flyback")) {
    pc_flyback(c, 24, 100e-6, 100e-6, 0.999, 20e-6, 10, 0.4, 10e-6);
    y0[3] = 1; *T = 1e-3;
  } else if (!strcmp(name, "fullbridge")) {
    pc_fullbridge(c, 100, 1e-3, 2.2e-6, 20, 100e-6, 1e-6, 25e-6);
    y0[2] = 1; *T = 10e-3;
  } else if (!strcmp(name, "sixpulse")) { pc_sixpulse(c, 100, 50, 2e-3, 470e-6, 10); y0[3] = 1; *T = 0.1; }
  else if (!strcmp(name, "precision-rectifier")) {
    pc_precision(c, 1, 50, 1e3, 2e3, 1e5, 1e3, 1e-6, 10e3);
    y0[2] = 1; *T = 0.1;
  } else return -1;
  return 0;
}

#endif
