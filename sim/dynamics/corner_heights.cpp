// A flat-faced die's corner heights in FixedStepper: every vertex's height from the orientation's
// bottom row by coordinate arrays, two at a time (soa_heights, soa_touching), and the lowest corner
// not in the contact set over the step's free motion, with its slope (lowest_flat).
#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dicesim {

double FixedStepper::soa_heights(const ContactSet& c, const Vec3& z_row, double* z) const {
  const int nv = soa_vertices_;
  constexpr double kInf = std::numeric_limits<double>::infinity();
#if defined(__SSE2__)
  const __m128d zx = _mm_set1_pd(z_row.x()), zy = _mm_set1_pd(z_row.y()), zz = _mm_set1_pd(z_row.z());
  for (int i = 0; i < nv; i += 2) {
    const __m128d h = _mm_add_pd(_mm_add_pd(_mm_mul_pd(zx, _mm_load_pd(vx_ + i)), _mm_mul_pd(zy, _mm_load_pd(vy_ + i))),
                                 _mm_mul_pd(zz, _mm_load_pd(vz_ + i)));
    _mm_store_pd(z + i, h);
  }
  for (int k = 0; k < c.n; ++k) z[c.vertex[k]] = kInf;
  if (nv % 2 == 1) z[nv] = z[nv - 1];  // the padding lane: the last vertex again, masked or not
  // The minimum of finite heights (never -0: a height is -0 only if all three products are) is
  // the same number in any order: two lanes, then the two (z < low ? z : low, as std::min).
  __m128d low = _mm_set1_pd(kInf);
  for (int i = 0; i < nv; i += 2) low = _mm_min_pd(_mm_load_pd(z + i), low);
  return _mm_cvtsd_f64(_mm_min_pd(_mm_unpackhi_pd(low, low), low));
#else
  const double zx = z_row.x(), zy = z_row.y(), zz = z_row.z();
  for (int i = 0; i < nv; ++i) z[i] = (zx * vx_[i] + zy * vy_[i]) + zz * vz_[i];
  for (int k = 0; k < c.n; ++k) z[c.vertex[k]] = kInf;
  double low = kInf;
  for (int i = 0; i < nv; ++i) low = std::min(low, z[i]);
  return low;
#endif
}

bool FixedStepper::soa_touching(const RigidState& s, ContactSet& c) const {
  const int nv = soa_vertices_;
  const double rounding = m_->rounding, tol = touch_tol_, pz = s.position.z();
  const double r20 = s.R(2, 0), r21 = s.R(2, 1), r22 = s.R(2, 2);
  int n = 0;
#if defined(__SSE2__)
  const __m128d x = _mm_set1_pd(r20), y = _mm_set1_pd(r21), z = _mm_set1_pd(r22);
  const __m128d p = _mm_set1_pd(pz), r = _mm_set1_pd(rounding), t = _mm_set1_pd(tol);
  for (int i = 0; i < nv; i += 2) {
    const __m128d h = _mm_sub_pd(
        _mm_add_pd(p, _mm_add_pd(_mm_mul_pd(x, _mm_load_pd(vx_ + i)),
                                 _mm_add_pd(_mm_mul_pd(y, _mm_load_pd(vy_ + i)), _mm_mul_pd(z, _mm_load_pd(vz_ + i))))),
        r);
    // touching_corners keeps a corner unless its height > tol (NaN included): not-greater-than.
    const int bits = _mm_movemask_pd(_mm_cmpngt_pd(h, t));
    if (bits == 0) continue;
    if (n + 2 > kMaxContacts) return false;
    if (bits & 1) c.vertex[n++] = i;
    if ((bits & 2) && i + 1 < nv) c.vertex[n++] = i + 1;  // (not an odd count's padding lane)
  }
#else
  for (int i = 0; i < nv; ++i) {
    const double h = (pz + (r20 * vx_[i] + (r21 * vy_[i] + r22 * vz_[i]))) - rounding;
    if (h > tol) continue;
    if (n + 1 > kMaxContacts) return false;
    c.vertex[n++] = i;
  }
#endif
  c.n = n;
  return true;
}

double FixedStepper::lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row, double t) const {
  if (soa_vertices_ > 0) {
    // Every corner's height two at a time (the same products and sums, in the same order, as
    // z_row.dot(vertex)), the contact set's corners masked out, and their minimum: the same
    // number as the loop below.
    alignas(16) double z[kSoaVertices];
    const double low = soa_heights(c, z_row, z);
    return p.z() + v.z() * t + low - m_->rounding;
  }
  const auto& verts = m_->vertices;
  const int nv = static_cast<int>(verts.size());
  double low = std::numeric_limits<double>::infinity();
  int j = 0;  // c.vertex is ascending
  for (int i = 0; i < nv; ++i) {
    if (j < c.n && c.vertex[j] == i) {
      ++j;
      continue;
    }
    low = std::min(low, z_row.dot(verts[i]));
  }
  return p.z() + v.z() * t + low - m_->rounding;  // a rounded corner touches with its ball
}

double FixedStepper::lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row,
                                 const Vec3& z_rate, double t, double& slope) const {
  if (soa_vertices_ > 0) {
    // As the loop below: the lowest corner's height, and its rate from the first corner (in vertex
    // order) at that height (the loop's strict < keeps the first).
    alignas(16) double z[kSoaVertices];
    const double low = soa_heights(c, z_row, z);
    int arg = -1;
    if (low < std::numeric_limits<double>::infinity())
      for (int i = 0; arg < 0; ++i)
        if (z[i] == low) arg = i;
    slope = v.z() + (arg >= 0 ? z_rate.dot(m_->vertices[static_cast<std::size_t>(arg)]) : 0.0);
    return p.z() + v.z() * t + low - m_->rounding;
  }
  const auto& verts = m_->vertices;
  const int nv = static_cast<int>(verts.size());
  double low = std::numeric_limits<double>::infinity();
  int arg = -1;
  int j = 0;  // c.vertex is ascending
  for (int i = 0; i < nv; ++i) {
    if (j < c.n && c.vertex[j] == i) {
      ++j;
      continue;
    }
    const double z = z_row.dot(verts[i]);
    if (z < low) low = z, arg = i;
  }
  slope = v.z() + (arg >= 0 ? z_rate.dot(verts[arg]) : 0.0);
  return p.z() + v.z() * t + low - m_->rounding;
}

}  // namespace dicesim
