#include "sim/dynamics/rest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "sim/body/outcome.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/sincos.hpp"

namespace dicesim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Each roll step lowers the COM, so the roll ends; the guard only bounds rounding trouble.
int roll_guard(const DieModel& m) { return 4 * (m.face_count() + m.vertex_count()) + 16; }

int roll_face(const DieModel& m, int f, double tiebreak, int& guard);

// Pivot about corner p (the lowest, on the floor) of the die in orientation R.
int roll_vertex(const DieModel& m, Mat3 R, int p, double tiebreak, int& guard) {
  const double tiny = 1e-12 * m.bounding_radius;
  while (guard-- > 0) {
    const Vec3 wp = R * m.vertices[static_cast<std::size_t>(p)];
    // 1. Pivot about corner p: the COM falls in the vertical plane through p and itself.
    Vec3 dh(-wp.x(), -wp.y(), 0.0);  // horizontal COM offset from p
    if (dh.norm() <= tiny) {         // COM straight above the corner: the toss decides the way
      const SinCos a = sincos_turns(tiebreak);  // the angle 2 pi tiebreak
      dh = Vec3(a.cos, a.sin, 0.0);
    }
    const Vec3 axis = Vec3::UnitZ().cross(dh).normalized();
    // The first theta in [0, pi] with A cos + B sin = 0 is atan2(A, -B); on [0, pi] the angle
    // grows with -cos(theta) = B / hypot(A, B), so the smallest is found, and its cos and sin are
    // known, without any trigonometric call. Only corners joined to p by an edge can touch first.
    int q = -1, q_edge = -1;
    double key = kInf, cos_t = 1.0, sin_t = 0.0;
    Vec3 wq = Vec3::Zero();
    const int adj0 = m.vertex_adj_begin[static_cast<std::size_t>(p)];
    const int adj1 = m.vertex_adj_begin[static_cast<std::size_t>(p) + 1];
    for (int a = adj0; a < adj1; ++a) {
      const int j = m.vertex_adj[static_cast<std::size_t>(a)];
      const Vec3 wj = R * m.vertices[static_cast<std::size_t>(j)];
      const Vec3 u = wj - wp;
      const double A = std::max(0.0, u.z()), B = axis.cross(u).z();
      const double h = std::sqrt(A * A + B * B);
      const double kk = h > 0.0 ? B / h : -1.0;  // (a degenerate edge: theta = 0)
      if (kk < key) {
        key = kk;
        q = j;
        q_edge = m.vertex_adj_edge[static_cast<std::size_t>(a)];
        wq = wj;
        cos_t = h > 0.0 ? -B / h : 1.0;
        sin_t = h > 0.0 ? A / h : 0.0;
      }
    }
    if (q < 0) return -1;
    // Rodrigues: rot = cos I + sin [axis]x + (1 - cos) axis axis^T.
    Mat3 cross_axis;
    cross_axis << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
    const Mat3 rot = cos_t * Mat3::Identity() + sin_t * cross_axis + (1.0 - cos_t) * (axis * axis.transpose());

    // 2. Edge p-q on the floor. If the COM projects beyond q, the die pivots on q alone.
    const Vec3 c = rot * (-wp);
    const Vec3 pq = rot * (wq - wp);
    const double len = pq.norm();
    const Vec3 e = pq / len;
    if (c.dot(e) > len * (1.0 + 1e-12)) {
      R = rot * R;
      p = q;
      continue;
    }
    // Tip about the edge toward the side of the COM: of the edge's two faces, the one whose
    // normal points more toward the COM's side goes down.
    Vec3 s = c - c.dot(e) * e;
    s.z() = 0.0;
    const int faces[2] = {m.loop_face[static_cast<std::size_t>(q_edge)], m.face_across[static_cast<std::size_t>(q_edge)]};
    const double s0 = (rot * R * m.face_normals[static_cast<std::size_t>(faces[0])]).dot(s);
    const double s1 = (rot * R * m.face_normals[static_cast<std::size_t>(faces[1])]).dot(s);
    int f;
    if (std::abs(s0 - s1) <= tiny)  // COM straight above the edge
      f = faces[std::fmod(tiebreak * 4096.0, 1.0) < 0.5 ? 0 : 1];
    else
      f = s0 > s1 ? faces[0] : faces[1];
    return roll_face(m, f, tiebreak, guard);
  }
  return -1;
}

// 3. Face f flat on the floor. If it cannot hold the COM, the die turns about the point of the
// face nearest the COM's foot: over that edge onto the face across, or about that corner.
int roll_face(const DieModel& m, int f, double tiebreak, int& guard) {
  while (guard-- > 0) {
    const std::size_t fi = static_cast<std::size_t>(f);
    if (m.face_hold[fi] >= 0.0) return f;
    const Vec3& n = m.face_normals[fi];
    const auto loop = m.face_vertices(f);
    const int k = static_cast<int>(loop.size());
    const Vec3 foot = n.dot(m.vertices[static_cast<std::size_t>(loop[0])]) * n;
    double best = kInf, best_t = 0.0;
    int best_k = 0;
    for (int i = 0; i < k; ++i) {
      const Vec3& A = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>(i)])];
      const Vec3& B = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>((i + 1) % k)])];
      const Vec3 ab = B - A;
      const double t = std::clamp((foot - A).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const double d = (foot - (A + t * ab)).squaredNorm();
      if (d < best) {
        best = d;
        best_t = t;
        best_k = i;
      }
    }
    constexpr double kEnd = 1e-9;
    if (best_t > kEnd && best_t < 1.0 - kEnd) {
      f = m.face_across[static_cast<std::size_t>(m.face_begin[fi] + best_k)];
      continue;
    }
    const int corner = loop[static_cast<std::size_t>(best_t <= kEnd ? best_k : (best_k + 1) % k)];
    const Mat3 R = Eigen::Quaterniond::FromTwoVectors(n, -Vec3::UnitZ()).toRotationMatrix();
    return roll_vertex(m, R, corner, tiebreak, guard);
  }
  return -1;
}

// A saddle between two different basins: the die balanced on an edge with its COM straight above
// it, at COM height `height`, the two sides rolling to basins a and b.
struct Saddle {
  int a, b;
  double height;
};

// Every edge once (from the face whose loop has it, to the face across).
std::vector<Saddle> basin_saddles(const DieModel& m) {
  const int nf = m.face_count();
  std::vector<int> basin(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    int guard = roll_guard(m);
    basin[static_cast<std::size_t>(f)] = roll_face(m, f, 0.5, guard);
  }
  std::vector<Saddle> out;
  for (int f = 0; f < nf; ++f) {
    const auto loop = m.face_vertices(f);
    const int k = static_cast<int>(loop.size());
    for (int i = 0; i < k; ++i) {
      const int g = m.face_across[static_cast<std::size_t>(m.face_begin[static_cast<std::size_t>(f)] + i)];
      if (g < f) continue;
      const Vec3& A = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>(i)])];
      const Vec3& B = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>((i + 1) % k)])];
      const Vec3 ab = B - A;
      const double t = (-A).dot(ab) / ab.squaredNorm();
      if (t < 0.0 || t > 1.0) continue;  // the COM projects beyond the edge: no balance on it
      const Vec3 w = -(A + t * ab);       // from the edge to the COM
      // Balanced on the edge, the floor's normal -w/|w| must lie between the two face normals:
      // -w = a n_f + b n_g with a, b >= 0 (all three are perpendicular to the edge).
      const Vec3& nf_ = m.face_normals[static_cast<std::size_t>(f)];
      const Vec3& ng = m.face_normals[static_cast<std::size_t>(g)];
      const double c = nf_.dot(ng), d1 = -w.dot(nf_), d2 = -w.dot(ng);
      const double det = 1.0 - c * c;
      if (det <= 0.0) continue;
      const double a = (d1 - c * d2) / det, b = (d2 - c * d1) / det;
      const double tol = -1e-12 * w.norm();
      if (a < tol || b < tol) continue;
      const int bf = basin[static_cast<std::size_t>(f)], bg = basin[static_cast<std::size_t>(g)];
      if (bf == bg || bf < 0 || bg < 0) continue;
      out.push_back({bf, bg, w.norm() + m.rounding});
    }
  }
  return out;
}

}  // namespace

void compute_escapes(DieModel& m) {
  const std::size_t F = static_cast<std::size_t>(m.face_count());
  if (!m.curved()) {  // a cylinder's face_escape is compute_rim_rest_geometry's
    const std::vector<Saddle> saddles = basin_saddles(m);
    m.face_escape.assign(F, kInf);
    for (const Saddle& sd : saddles) {
      m.face_escape[static_cast<std::size_t>(sd.a)] = std::min(m.face_escape[static_cast<std::size_t>(sd.a)], sd.height);
      m.face_escape[static_cast<std::size_t>(sd.b)] = std::min(m.face_escape[static_cast<std::size_t>(sd.b)], sd.height);
    }
    m.outcome_escape = m.face_escape;
    auto outcome = [&](std::size_t f) { return resting_outcome_label(m, static_cast<int>(f)); };
    // Per basin A: the least, over paths of saddles, of the highest saddle on the path (a minimax
    // Dijkstra over the few basins), to every basin; the least of it over the basins read otherwise.
    std::vector<double> pass(F);
    std::vector<char> done(F);
    for (std::size_t a = 0; a < F; ++a) {
      if (!std::isfinite(m.face_escape[a])) continue;  // not a basin with a way out
      std::fill(pass.begin(), pass.end(), kInf);
      std::fill(done.begin(), done.end(), 0);
      pass[a] = -kInf;
      double out = kInf;
      for (;;) {
        std::size_t u = F;
        for (std::size_t v = 0; v < F; ++v)
          if (!done[v] && pass[v] < kInf && (u == F || pass[v] < pass[u])) u = v;
        if (u == F || pass[u] >= out) break;
        done[u] = 1;
        if (outcome(u) != outcome(a)) {
          out = std::min(out, pass[u]);
          continue;
        }
        for (const Saddle& sd : saddles) {
          const std::size_t x = static_cast<std::size_t>(sd.a), y = static_cast<std::size_t>(sd.b);
          const std::size_t v = x == u ? y : y == u ? x : F;
          if (v < F && !done[v]) pass[v] = std::min(pass[v], std::max(pass[u], sd.height));
        }
      }
      m.outcome_escape[a] = out;
    }
  } else {
    m.outcome_escape = m.face_escape;
  }
  m.max_escape = 0.0;
  bool any_finite = false;
  for (std::size_t f = 0; f < F; ++f)
    if (std::isfinite(m.outcome_escape[f]) && (!m.curved() || m.face_hold[f] >= 0.0)) {
      m.max_escape = std::max(m.max_escape, m.outcome_escape[f]);
      any_finite = true;
    }
  if (!any_finite) m.max_escape = kInf;  // one outcome only: every toss ends on it
}

void compute_rest_geometry(DieModel& m) {
  const int nf = m.face_count();
  const std::size_t F = static_cast<std::size_t>(nf);
  m.face_height.assign(F, 0.0);
  m.face_hold.assign(F, 0.0);
  m.face_tip_ratio.assign(F, 0.0);
  m.face_gyro.assign(F, 0.0);
  m.face_area.assign(F, 0.0);
  const Mat3 I = m.principal_moments.asDiagonal();
  for (int f = 0; f < nf; ++f) {
    const std::size_t fi = static_cast<std::size_t>(f);
    const Vec3& n = m.face_normals[fi];
    const auto loop = m.face_vertices(f);
    const int k = static_cast<int>(loop.size());
    const double h = n.dot(m.vertices[static_cast<std::size_t>(loop[0])]);
    const Vec3 foot = h * n;  // the COM's projection on the face plane
    double hold = kInf;
    Vec3 area2 = Vec3::Zero();
    for (int i = 0; i < k; ++i) {
      const Vec3& A = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>(i)])];
      const Vec3& B = m.vertices[static_cast<std::size_t>(loop[static_cast<std::size_t>((i + 1) % k)])];
      const Vec3 inward = n.cross((B - A).normalized());  // counter-clockwise from outside
      hold = std::min(hold, (foot - A).dot(inward));
      area2 += A.cross(B);
    }
    m.face_height[fi] = h + m.rounding;
    m.face_hold[fi] = hold;  // < 0: the face cannot hold the COM
    m.face_tip_ratio[fi] = hold / (h + m.rounding);
    m.face_gyro[fi] = n.cross(I * n).norm();
    m.face_area[fi] = 0.5 * std::abs(area2.dot(n));
  }
}

int quasi_static_down_face(const DieModel& m, const Mat3& R, double tiebreak) {
  if (m.curved()) return rim_quasi_static_down(m, R, tiebreak);
  int p = 0;
  double low = kInf;
  const int nv = m.vertex_count();
  for (int i = 0; i < nv; ++i) {
    const double z = R.row(2).dot(m.vertices[static_cast<std::size_t>(i)]);
    if (z < low) {
      low = z;
      p = i;
    }
  }
  int guard = roll_guard(m);
  return roll_vertex(m, R, p, tiebreak, guard);
}

int roll_from_face(const DieModel& m, int f, double tiebreak) {
  int guard = roll_guard(m);
  return roll_face(m, f, tiebreak, guard);
}

int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak) {
  return rest_face_down(m, s, tiebreak, kinetic_energy(m, s));
}

int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak, double ke) {
  if (m.curved()) return rim_rest_face_down(m, s, tiebreak, ke);
  const double mg = m.mass * m.gravity;
  // Energy above every basin's barrier and no corner can reach the floor: neither criterion can
  // hold (cheap; the flights' and the air steps' rest checks end here).
  const bool above_barriers = ke + mg * s.position.z() >= mg * m.max_escape;
  if (above_barriers && s.position.z() > m.bounding_radius) return -1;

  double low = kInf;
  for (const Vec3& v : m.vertices) low = std::min(low, s.R.row(2).dot(v));
  low += s.position.z() - m.rounding;

  // Lying flat on the face most nearly down, sliding or spinning but not rocking. Whatever its
  // kinetic energy (rest.hpp): the energy gate above must not decide this one.
  const double flat_tol = 1e-6 * m.bounding_radius;
  if (low <= flat_tol) {
    int down = 0;
    double down_z = 2.0;
    const int nf = m.face_count();
    for (int f = 0; f < nf; ++f) {
      const double z = s.R.row(2).dot(m.face_normals[static_cast<std::size_t>(f)]);
      if (z < down_z) {
        down_z = z;
        down = f;
      }
    }
    const std::size_t di = static_cast<std::size_t>(down);
    const double v_tol = rest_speed_tol(m);
    // The largest spin the flat motion can ever reach: all of its kinetic energy (friction only
    // removes it) in the spin about the face's normal n, w^2 <= 2 ke / (n . I n).
    const Vec3& n = m.face_normals[di];
    const double spin_max2 = 2.0 * ke / n.dot(m.principal_moments.cwiseProduct(n));
    // Friction shifts the centre of pressure needed by at most mu h, the gyroscopic torque by
    // w^2 |n x I n| / (m g): together within face_hold (rest.hpp).
    if (down_z < -0.999 && m.face_hold[di] > 0.0 &&
        m.max_friction * m.face_height[di] + spin_max2 * m.face_gyro[di] / mg < 0.999 * m.face_hold[di]) {
      bool flat = true;
      for (const int v : m.face_vertices(down)) {
        if (!flat) break;
        const Vec3 r = s.R * m.vertices[static_cast<std::size_t>(v)];
        flat = s.position.z() + r.z() - m.rounding - std::min(low, 0.0) <= flat_tol &&
               std::abs((s.velocity + s.omega.cross(r)).z()) <= v_tol;
      }
      if (flat) return down;
    }
  }

  if (above_barriers) return -1;
  const double energy = ke + mg * (s.position.z() + std::max(0.0, -low));
  const int basin = quasi_static_down_face(m, s.R, tiebreak);
  if (basin >= 0 && energy < mg * m.outcome_escape[static_cast<std::size_t>(basin)] * (1.0 - 1e-9)) return basin;
  return -1;
}

}  // namespace dicesim
