#include "sim/dynamics/flight.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dicesim {
namespace {

// A rim circle's height over the floor at time s ahead is bounded below, point by point, by
//   z(phi) + zdot(phi) s - A s^2 / 2  =  a0 + a1 s - rho |p + q s| - A s^2 / 2  =: g(s)
// (z, zdot sinusoids in the rim angle phi; its minimum over phi in closed form). g is concave and
// g(0) is the rim's lowest height, so every s in (0, s*] with g(s) >= 0 is a step that cannot pass
// a contact. Chords of a concave g lie below it: from a safe point and an overshoot (Newton from
// the right stays right of s*), the chord's zero is a new safe point. Returns a safe step.
double rim_safe_step(double a0, double a1, const Eigen::Vector2d& p, const Eigen::Vector2d& q, double rho,
                     double A) {
  const auto g = [&](double s) { return a0 + a1 * s - rho * (p + q * s).norm() - 0.5 * A * s * s; };
  const auto dg = [&](double s) {
    const Eigen::Vector2d x = p + q * s;
    const double n = x.norm();
    return a1 - (n > 0.0 ? rho * x.dot(q) / n : -rho * q.norm()) - A * s;
  };
  // A rim slightly below the floor but rising counts as on it (as a corner does): g(0) = 0.
  const double z = g(0.0);
  if (z < 0.0) a0 -= z;
  const double z0 = std::max(0.0, z);
  // Safe: every rim point at least as low and falling as fast as the worst of them.
  const double vmin = a1 - rho * q.norm();
  double lo = (vmin + std::sqrt(vmin * vmin + 2.0 * A * z0)) / A;
  // Overshoot: the lowest point's own bound (g is below it).
  const double vlow = dg(0.0);
  double hi = (vlow + std::sqrt(vlow * vlow + 2.0 * A * z0)) / A;
  if (!(hi > lo)) return lo;
  double g_lo = g(lo), g_hi = g(hi);
  if (g_hi >= 0.0) return hi;
  for (int it = 0; it < 6 && hi - lo > 1e-3 * hi; ++it) {
    // The chord's zero is safe when g(lo) > 0; from g(lo) = 0, halve the bracket instead.
    const double c = g_lo > 0.0 ? lo + g_lo * (hi - lo) / (g_lo - g_hi) : 0.5 * (lo + hi);
    const double gc = g(c);
    if (gc >= 0.0) {
      lo = c, g_lo = gc;
    } else {
      hi = c, g_hi = gc;
    }
    const double d = dg(hi);
    if (d < 0.0) {
      const double nw = hi - g_hi / d;  // Newton from the right: still an overshoot
      if (nw > lo && nw < hi) hi = nw, g_hi = g(hi);
    }
    if (g_hi >= 0.0) return hi;
  }
  return lo;
}

}  // namespace

Flight::Flight(const DieModel& model, const RigidState& s)
    : model_(&model),
      p0_(s.position),
      v0_(s.velocity),
      // R (I * (R^T omega)): 21 products where R diag(I) R^T omega took 54.
      rotation_(model.principal_moments, s.R, world_angular_momentum(model, s.R, s.omega)) {
  const double r = model.bounding_radius;
  // z_i'' = -g + (alpha x p + omega x (omega x p))_z, so |z_i'' + g| <= r (|omega|^2 + |alpha|).
  const double w = rotation_.max_omega();
  accel_bound_ = model.gravity + r * (w * w + rotation_.max_alpha());
  contact_tol_ = 1e-9 * r;
}

RigidState Flight::state_with(double t, const Mat3& R, const Vec3& omega) const {
  RigidState s;
  s.position = p0_ + v0_ * t;
  s.position.z() -= 0.5 * model_->gravity * t * t;
  s.velocity = v0_;
  s.velocity.z() -= model_->gravity * t;
  s.R = R;
  s.omega = omega;
  return s;
}

RigidState Flight::state(double t) const {
  Mat3 R;
  Vec3 w;
  rotation_.state(t, R, w);
  return state_with(t, R, w);
}

namespace {

// Corner heights above the floor, their rates, and the numerators of the advancement step,
// zdot + sqrt(zdot^2 + 2 A max(z, 0)), for corners [0, n) (n rounded up to even: the arrays have
// room). Every number is the same operation, in the same order, as the one-corner-at-a-time
// expression (p = R v as Eigen 3.4 with SSE2 evaluates it: rows x and y as (R_i0 v0 + R_i1 v1) + R_i2 v2, row z as
// R_20 v0 + (R_21 v1 + R_22 v2); tests/test_flight_search.cpp checks that the two paths agree), so the search is
// bit-identical with or without SIMD; SSE2 does two corners per instruction.
struct CornerPass {
  double R[9];  // row-major
  double zc, vz, wx, wy, rounding, two_A;
  double tol;   // a corner at most this high and moving down touches
};

// Also returns whether any corner touches (z <= tol, zdot < 0) and, if none does, sets min_num to
// the smallest numerator: the search's own loop (next_contact) would find the same number, the
// minimum of values that are never NaN or -0 (zdot + sqrt(zdot^2 + ...) >= +0, or a tiny
// negative where zdot^2 underflows), in any order. If one does, the loop runs as before.
bool corner_pass(const CornerPass& c, int n, const double* vx, const double* vy, const double* vzs, double* z,
                 double* zdot, double* num, double& min_num) {
#if defined(__SSE2__)
  const __m128d r00 = _mm_set1_pd(c.R[0]), r01 = _mm_set1_pd(c.R[1]), r02 = _mm_set1_pd(c.R[2]);
  const __m128d r10 = _mm_set1_pd(c.R[3]), r11 = _mm_set1_pd(c.R[4]), r12 = _mm_set1_pd(c.R[5]);
  const __m128d r20 = _mm_set1_pd(c.R[6]), r21 = _mm_set1_pd(c.R[7]), r22 = _mm_set1_pd(c.R[8]);
  const __m128d zc = _mm_set1_pd(c.zc), vz = _mm_set1_pd(c.vz), wx = _mm_set1_pd(c.wx), wy = _mm_set1_pd(c.wy);
  const __m128d rounding = _mm_set1_pd(c.rounding), two_A = _mm_set1_pd(c.two_A), zero = _mm_setzero_pd();
  const __m128d tol = _mm_set1_pd(c.tol);
  __m128d touch = _mm_setzero_pd(), low = _mm_set1_pd(std::numeric_limits<double>::infinity());
  for (int i = 0; i < n; i += 2) {
    const __m128d x = _mm_load_pd(vx + i), y = _mm_load_pd(vy + i), w = _mm_load_pd(vzs + i);
    const __m128d px = _mm_add_pd(_mm_add_pd(_mm_mul_pd(r00, x), _mm_mul_pd(r01, y)), _mm_mul_pd(r02, w));
    const __m128d py = _mm_add_pd(_mm_add_pd(_mm_mul_pd(r10, x), _mm_mul_pd(r11, y)), _mm_mul_pd(r12, w));
    const __m128d pz = _mm_add_pd(_mm_mul_pd(r20, x), _mm_add_pd(_mm_mul_pd(r21, y), _mm_mul_pd(r22, w)));
    const __m128d zi = _mm_sub_pd(_mm_add_pd(zc, pz), rounding);
    const __m128d zdi = _mm_add_pd(vz, _mm_sub_pd(_mm_mul_pd(wx, py), _mm_mul_pd(wy, px)));
    const __m128d zp = _mm_max_pd(zero, zi);  // = std::max(z, 0.0), NaN and -0 included
    const __m128d root = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(zdi, zdi), _mm_mul_pd(two_A, zp)));
    _mm_store_pd(z + i, zi);
    _mm_store_pd(zdot + i, zdi);
    const __m128d ni = _mm_add_pd(zdi, root);
    _mm_store_pd(num + i, ni);
    // (The padding lane of an odd count repeats the last corner: nothing new. num < low ? num : low,
    // as std::min(low, num); a touching corner's num too, but then the caller's loop decides.)
    touch = _mm_or_pd(touch, _mm_and_pd(_mm_cmple_pd(zi, tol), _mm_cmplt_pd(zdi, zero)));
    low = _mm_min_pd(ni, low);
  }
  if (_mm_movemask_pd(touch) != 0) return true;
  low = _mm_min_pd(low, _mm_unpackhi_pd(low, low));
  min_num = _mm_cvtsd_f64(low);
  return false;
#else
  for (int i = 0; i < n; ++i) {
    const double px = (c.R[0] * vx[i] + c.R[1] * vy[i]) + c.R[2] * vzs[i];
    const double py = (c.R[3] * vx[i] + c.R[4] * vy[i]) + c.R[5] * vzs[i];
    const double pz = c.R[6] * vx[i] + (c.R[7] * vy[i] + c.R[8] * vzs[i]);
    z[i] = c.zc + pz - c.rounding;
    zdot[i] = c.vz + (c.wx * py - c.wy * px);
    num[i] = zdot[i] + std::sqrt(zdot[i] * zdot[i] + c.two_A * std::max(z[i], 0.0));
  }
  min_num = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    if (z[i] <= c.tol && zdot[i] < 0.0) return true;
    min_num = std::min(min_num, num[i]);
  }
  return false;
#endif
}

// Dies with more corners than this search them one at a time (the same numbers, slower).
constexpr int kSoaCorners = 64;

}  // namespace

ContactSearch Flight::next_contact(double t_limit) const {
  const double g = model_->gravity;
  const double A = accel_bound_;
  ContactSearch out;

  // No vertex can touch while the COM is higher than the bounding radius: whenever it is, jump
  // in closed form to the time it comes back down to that height (the whole free fall of a high
  // throw, or the rise and fall after a strong bounce, costs one square root).
  // sphere_time: the later root of z_com(t) = bounding radius, when the COM is on its way down.
  const double clear = p0_.z() - model_->bounding_radius;
  const double disc = v0_.z() * v0_.z() + 2.0 * g * clear;
  const double sphere_time = disc >= 0.0 ? (v0_.z() + std::sqrt(disc)) / g : 0.0;
  double t = clear > 0.0 ? sphere_time : 0.0;

  // Second-order conservative advancement: vertex i satisfies
  //   z_i(t + s) >= z_i + zdot_i s - A s^2 / 2,
  // so the smallest root of that bound over all vertices is a step that cannot pass a contact.
  // Near a contact it converges quadratically (like Newton's method from the safe side).
  constexpr int kMaxIterations = 100000;
  const double min_step = 1e-15;
  const int n = model_->curved() ? 0 : model_->vertex_count();  // a cylinder has rims, not corners
  const double rounding = model_->rounding;
  // The corners as a structure of arrays (padded to an even count), for corner_pass.
  const bool soa = n <= kSoaCorners;
  alignas(16) double cx[kSoaCorners], cy[kSoaCorners], cz[kSoaCorners];
  alignas(16) double z_of[kSoaCorners], zdot_of[kSoaCorners], num_of[kSoaCorners];
  if (soa) {
    for (int i = 0; i < n; ++i) {
      const Vec3& v = model_->vertices[static_cast<std::size_t>(i)];
      cx[i] = v.x(), cy[i] = v.y(), cz[i] = v.z();
    }
    // A padding lane, the last corner again: computed, never read one by one, and the same as
    // that corner in corner_pass's minimum and touch test.
    if (n % 2 == 1) cx[n] = cx[n - 1], cy[n] = cy[n - 1], cz[n] = cz[n - 1];
  }
  for (int it = 0; it < kMaxIterations; ++it) {
    out.iterations = it + 1;
    if (t > t_limit) {
      out.outcome = ContactSearch::Outcome::TimeLimit;
      out.t = t_limit;
      return out;
    }
    // Above the bounding sphere no corner can touch: jump before evaluating the rotation.
    const double zc = p0_.z() + v0_.z() * t - 0.5 * g * t * t;
    if (zc > model_->bounding_radius && sphere_time > t) {
      t = sphere_time;
      continue;
    }
    Mat3 R;
    Vec3 w;
    rotation_.state(t, R, w);
    const double vz = v0_.z() - g * t;

    // The step is min_i (zdot_i + sqrt(zdot_i^2 + 2 A z_i)) / A; division by A > 0 is monotone
    // under rounding, so dividing the smallest numerator once gives the same number.
    double numerator = std::numeric_limits<double>::infinity();
    int touching = -1;
    double touching_z = std::numeric_limits<double>::infinity();
    double rim_step = std::numeric_limits<double>::infinity();  // a cylinder: its rims' safe step
    if (model_->curved()) {
      // Each rim circle: its lowest point in closed form; the rim touches when that point is on
      // the floor and its material point moves down (feature 3 k: the rim's lowest point).
      const Rims& rim = model_->rims;
      const Vec3 K = R * rim.axis, e1 = R * rim.perp, e2 = K.cross(e1);
      const Vec3 o = R * rim.centre;
      for (int k = 0; k < 2; ++k) {
        const Vec3 c = o + (k == 0 ? rim.half : -rim.half) * K;
        const double a0 = zc + c.z() - rounding;
        const double a1 = vz + (w.x() * c.y() - w.y() * c.x());
        const Eigen::Vector2d p(e1.z(), e2.z());
        const Eigen::Vector2d q(w.x() * e1.y() - w.y() * e1.x(), w.x() * e2.y() - w.y() * e2.x());
        const double pn = p.norm();
        const double z = a0 - rim.radius * pn;
        // The lowest point's velocity (a flat rim: every point is lowest, take the fastest down).
        const double zdot = pn > 1e-12 ? a1 - rim.radius * p.dot(q) / pn : a1 - rim.radius * q.norm();
        if (z <= contact_tol_ && zdot < 0.0) {
          if (z < touching_z) {
            touching = 3 * k;
            touching_z = z;
          }
          continue;
        }
        rim_step = std::min(rim_step, rim_safe_step(a0, a1, p, q, rim.radius, A));
      }
    }
    if (soa) {
      const CornerPass pass{{R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)},
                            zc, vz, w.x(), w.y(), rounding, 2.0 * A, contact_tol_};
      double min_num;
      if (!corner_pass(pass, n, cx, cy, cz, z_of, zdot_of, num_of, min_num)) {
        // No corner touching (every iteration but the last): the numerators' minimum from the pass.
        numerator = std::min(numerator, min_num);
      } else {
        for (int i = 0; i < n; ++i) {
          if (z_of[i] <= contact_tol_ && zdot_of[i] < 0.0) {
            if (z_of[i] < touching_z) {
              touching = i;
              touching_z = z_of[i];
            }
            continue;
          }
          numerator = std::min(numerator, num_of[i]);
        }
      }
    } else {
      for (int i = 0; i < n; ++i) {
        const Vec3 p = R * model_->vertices[static_cast<std::size_t>(i)];
        const double z = zc + p.z() - rounding;  // the lowest point of the corner's ball
        const double zdot = vz + (w.x() * p.y() - w.y() * p.x());
        if (z <= contact_tol_ && zdot < 0.0) {
          if (z < touching_z) {
            touching = i;
            touching_z = z;
          }
          continue;
        }
        const double zp = std::max(z, 0.0);
        numerator = std::min(numerator, zdot + std::sqrt(zdot * zdot + 2.0 * A * zp));
      }
    }
    if (touching >= 0) {
      out.outcome = ContactSearch::Outcome::Contact;
      out.t = t;
      out.vertex = touching;
      out.at = state_with(t, R, w);
      return out;
    }
    t += std::max(std::min(numerator / A, rim_step), min_step * (1.0 + t));
  }
  out.outcome = ContactSearch::Outcome::IterationLimit;
  out.t = t;
  return out;
}

}  // namespace dicesim
