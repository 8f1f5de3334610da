/* trig — sin for the time loop's inputs, inlined: Cody-Waite reduction by
 * pi/2 in three parts (each part has 33 bits, so k times it is exact for
 * |k| < 2^20) and the Taylor series of sin and cos on [-pi/4, pi/4] to
 * degree 17 and 16 (truncation below 1e-17). Within 2 ulp of libm's sin
 * (tests/test_input.c measures it), for about half its instructions and no
 * call; arguments of 65536 and more, Inf and NaN go to libm. */
#ifndef CUP_UTIL_TRIG_H
#define CUP_UTIL_TRIG_H

#include <math.h>

static inline double cup_sin(double x) {
  double ax = fabs(x);
  if (!(ax < 65536.0)) return sin(x);
  if (ax < 0x1p-26) return x;                       /* sin x rounds to x (and keeps the sign of 0) */
  const double round = 0x1.8p52;                    /* adding it rounds to an integer */
  double k = (x * 0x1.45f306dc9c883p-1 + round) - round;   /* nearest integer to x 2/pi */
  double r = ((x - k * 0x1.921fb544p+0) - k * 0x1.0b4611a6p-34) - k * 0x1.3198a2e037073p-69;
  double r2 = r * r;
  double s = r + r * r2 * (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 +
             r2 * (-2.505210838544172e-08 + r2 * (1.6059043836821613e-10 + r2 * (-7.647163731819816e-13 +
             r2 * 2.8114572543455206e-15)))))));
  double c = 1 + r2 * (-0.5 + r2 * (1.0 / 24 + r2 * (-1.0 / 720 + r2 * (2.48015873015873e-05 +
             r2 * (-2.755731922398589e-07 + r2 * (2.08767569878681e-09 + r2 * (-1.1470745597729725e-11 +
             r2 * 4.779477332387385e-14)))))));
  long q = (long)k;                                 /* the quadrant, mod 4 */
  double v = (q & 1) ? c : s;
  return (q & 2) ? -v : v;
}

#endif
