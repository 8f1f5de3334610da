/* trig — sin for the time loop's inputs, inlined: Cody-Waite reduction by
 * pi/2 in three parts (each part has 33 bits, so k times it is exact for
 * |k| < 2^20) and the Taylor series of sin and cos on [-pi/4, pi/4] to
 * degree 17 and 16 (truncation below 1e-17). Within 2 ulp of libm's sin
 * (tests/test_input.c measures it), for about half its instructions and no
 * call; arguments of 65536 and more, Inf and NaN go to libm. */
#ifndef CUP_UTIL_TRIG_H
#define CUP_UTIL_TRIG_H

#include <math.h>
#include "lanes.h"

/* The reduction and both series, for a scalar or for lanes (T double or
 * v2d): r = x - k pi/2 with y = 1.5 2^52 + k, and s, c ~ sin r, cos r. */
#define CUP_SIN_CORE(T, x, y, s, c)                                                                     \
  const T y = x * 0x1.45f306dc9c883p-1 + 0x1.8p52;   /* adding 1.5 2^52 rounds x 2/pi to an integer */ \
  const T k_ = y - 0x1.8p52;                                                                          \
  const T r_ = ((x - k_ * 0x1.921fb544p+0) - k_ * 0x1.0b4611a6p-34) - k_ * 0x1.3198a2e037073p-69;     \
  const T r2_ = r_ * r_;                                                                              \
  const T s = r_ + r_ * r2_ * (-1.0 / 6 + r2_ * (1.0 / 120 + r2_ * (-1.0 / 5040 + r2_ * (1.0 / 362880 + \
              r2_ * (-2.505210838544172e-08 + r2_ * (1.6059043836821613e-10 +                        \
              r2_ * (-7.647163731819816e-13 + r2_ * 2.8114572543455206e-15)))))));                    \
  const T c = 1 + r2_ * (-0.5 + r2_ * (1.0 / 24 + r2_ * (-1.0 / 720 + r2_ * (2.48015873015873e-05 +     \
              r2_ * (-2.755731922398589e-07 + r2_ * (2.08767569878681e-09 +                          \
              r2_ * (-1.1470745597729725e-11 + r2_ * 4.779477332387385e-14)))))))

static inline double trig_sin(double x) {
  double ax = fabs(x);
  if (!(ax < 65536.0)) return sin(x);
  if (ax < 0x1p-26) return x;                       /* sin x rounds to x (and keeps the sign of 0) */
  CUP_SIN_CORE(double, x, y, s, c);
  long q = (long)(y - 0x1.8p52);                    /* the quadrant, mod 4 */
  double v = (q & 1) ? c : s;
  return (q & 2) ? -v : v;
}

/* trig_sin of both lanes, bit for bit, in fewer instructions than two: the
 * quadrant from y's low mantissa bits (y = 1.5 2^52 + k holds k + 2^51
 * there, and 2^51 = 0 mod 4). */
static inline v2d trig_sin2(v2d x) {
  v2d ax = v2_abs(x);
  v2l fits = ax < (v2d){65536.0, 65536.0};
  if (!(fits[0] & fits[1])) return (v2d){trig_sin(x[0]), trig_sin(x[1])};
  CUP_SIN_CORE(v2d, x, y, s, c);
  v2l q = (v2l)y;
  v2d v = v2_select(-(q & 1), c, s);
  v = (v2d)((v2l)v ^ ((q & 2) << 62));
  return v2_select(ax < (v2d){0x1p-26, 0x1p-26}, x, v);
}

#endif
