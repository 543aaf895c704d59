// Illinois: regula falsi that halves the weight of an end kept twice running. Superlinear on a
// smooth function, and it never leaves the bracket. The caller owns the evaluations and the
// stopping rule; this holds the bracket and chooses the next point.
#pragma once

namespace dicesim {

struct Illinois {
  double lo, f_lo, hi, f_hi;  // the ends' values have opposite signs
  int side = 0;               // which end moved last: -1 lo, +1 hi

  // The secant's root through the (weighted) ends; the midpoint if rounding puts it outside.
  double next() const {
    const double x = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    return x > lo && x < hi ? x : 0.5 * (lo + hi);
  }

  // f = f(x), on lo's side of the root or not: x replaces that end.
  void update(double x, double f, bool lo_side) {
    if (lo_side) {
      lo = x, f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = x, f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
};

}  // namespace dicesim
