#include "sim/dynamics/rest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dicesim {
namespace {

// The face that shares edge (a, b) with face f (a and b are corners of f that differ in one bit).
int face_across(int f, int a, int b) {
  const int k = __builtin_ctz(static_cast<unsigned>(a ^ b));  // the edge runs along axis k
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == k || axis == f / 2) continue;
    return 2 * axis + (((a >> axis) & 1) ? 0 : 1);
  }
  return f;
}

}  // namespace

void compute_rest_geometry(DieModel& m) {
  m.max_escape = 0.0;
  for (int f = 0; f < 6; ++f) {
    const int a = f / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    const int plus = (f % 2 == 0) ? 1 : 0;
    const int bits[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 4; ++k) m.face_vertices[f][k] = (plus << a) | (bits[k][0] << b) | (bits[k][1] << c);
    const Vec3& n = m.face_normals[f];
    const double h = n.dot(m.vertices[m.face_vertices[f][0]]);
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centroid += 0.25 * m.vertices[m.face_vertices[f][k]];
    const Vec3 foot = h * n;  // the COM's projection on the face plane
    double escape = std::numeric_limits<double>::infinity(), tip = escape;
    for (int k = 0; k < 4; ++k) {
      const Vec3& A = m.vertices[m.face_vertices[f][k]];
      const Vec3& B = m.vertices[m.face_vertices[f][(k + 1) % 4]];
      const Vec3 e = (B - A).normalized();
      escape = std::min(escape, A.cross(e).norm());
      Vec3 inward = n.cross(e);
      if ((centroid - A).dot(inward) < 0.0) inward = -inward;
      tip = std::min(tip, (foot - A).dot(inward) / h);
    }
    m.face_height[f] = h;
    m.face_escape[f] = escape;
    m.face_tip_ratio[f] = tip;  // < 0: the face cannot hold the COM (never for a box: COM inside)
    m.max_escape = std::max(m.max_escape, escape);
  }
}

int quasi_static_down_face(const DieModel& m, const Mat3& R, double tiebreak) {
  Vec3 w[8];
  int p = 0;
  for (int i = 0; i < 8; ++i) {
    w[i] = R * m.vertices[i];
    if (w[i].z() < w[p].z()) p = i;
  }
  const double tiny = 1e-12 * m.bounding_radius;

  // 1. Pivot about corner p: the COM falls in the vertical plane through p and itself.
  Vec3 dh(-w[p].x(), -w[p].y(), 0.0);  // horizontal COM offset from p
  if (dh.norm() <= tiny) {             // COM straight above the corner: the toss decides the way
    const double a = 2.0 * kPi * tiebreak;
    dh = Vec3(std::cos(a), std::sin(a), 0.0);
  }
  const Vec3 axis = Vec3::UnitZ().cross(dh).normalized();
  // The first theta in [0, pi] with A cos + B sin = 0 is atan2(A, -B); on [0, pi] the angle
  // grows with -cos(theta) = B / hypot(A, B), so the smallest is found, and its cos and sin are
  // known, without any trigonometric call.
  int q = -1;
  double key = std::numeric_limits<double>::infinity(), cos_t = 1.0, sin_t = 0.0;
  for (int k = 0; k < 3; ++k) {
    const int j = p ^ (1 << k);
    const Vec3 u = w[j] - w[p];
    const double A = std::max(0.0, u.z()), B = axis.cross(u).z();
    const double h = std::sqrt(A * A + B * B);
    const double kk = h > 0.0 ? B / h : -1.0;  // (a degenerate edge: theta = 0)
    if (kk < key) {
      key = kk;
      q = j;
      cos_t = h > 0.0 ? -B / h : 1.0;
      sin_t = h > 0.0 ? A / h : 0.0;
    }
  }
  // Rodrigues: rot = cos I + sin [axis]x + (1 - cos) axis axis^T.
  Mat3 cross_axis;
  cross_axis << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
  const Mat3 rot = cos_t * Mat3::Identity() + sin_t * cross_axis + (1.0 - cos_t) * (axis * axis.transpose());

  // 2. Tip about edge p-q toward the side of the COM.
  const Vec3 c = rot * (-w[p]);
  const Vec3 e = (rot * (w[q] - w[p])).normalized();
  Vec3 s = c - c.dot(e) * e;
  s.z() = 0.0;
  const int k = __builtin_ctz(static_cast<unsigned>(p ^ q));
  int faces[2], nf = 0;
  for (int ax = 0; ax < 3 && nf < 2; ++ax)
    if (ax != k) faces[nf++] = 2 * ax + (((p >> ax) & 1) ? 0 : 1);
  const double s0 = (rot * R * m.face_normals[faces[0]]).dot(s);
  const double s1 = (rot * R * m.face_normals[faces[1]]).dot(s);
  int f;
  if (std::abs(s0 - s1) <= tiny)  // COM straight above the edge
    f = faces[std::fmod(tiebreak * 4096.0, 1.0) < 0.5 ? 0 : 1];
  else
    f = s0 > s1 ? faces[0] : faces[1];

  // 3. A face that cannot hold the COM tips over its worst edge (never happens for a box).
  for (int guard = 0; guard < 6 && m.face_tip_ratio[f] < 0.0; ++guard) {
    const Vec3 foot = m.face_height[f] * m.face_normals[f];
    int best = 0;
    double worst = std::numeric_limits<double>::infinity();
    for (int j = 0; j < 4; ++j) {
      const Vec3& A = m.vertices[m.face_vertices[f][j]];
      const Vec3& B = m.vertices[m.face_vertices[f][(j + 1) % 4]];
      Vec3 inward = m.face_normals[f].cross((B - A).normalized());
      Vec3 centroid = Vec3::Zero();
      for (int i = 0; i < 4; ++i) centroid += 0.25 * m.vertices[m.face_vertices[f][i]];
      if ((centroid - A).dot(inward) < 0.0) inward = -inward;
      const double d = (foot - A).dot(inward);
      if (d < worst) {
        worst = d;
        best = j;
      }
    }
    f = face_across(f, m.face_vertices[f][best], m.face_vertices[f][(best + 1) % 4]);
  }
  return f;
}

int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak) {
  const Vec3 wb = s.R.transpose() * s.omega;
  const double ke = 0.5 * m.mass * s.velocity.squaredNorm() + 0.5 * wb.dot(m.principal_moments.cwiseProduct(wb));
  const double mg = m.mass * m.gravity;
  if (ke + mg * s.position.z() >= mg * m.max_escape) return -1;  // cheap: no basin can hold it yet

  double low = std::numeric_limits<double>::infinity();
  for (const Vec3& v : m.vertices) low = std::min(low, s.R.row(2).dot(v));
  low += s.position.z();
  const double energy = ke + mg * (s.position.z() + std::max(0.0, -low));

  // Lying flat on the face most nearly down, sliding or spinning but not rocking.
  int down = 0;
  double down_z = 2.0;
  for (int f = 0; f < 6; ++f) {
    const double z = s.R.row(2).dot(m.face_normals[f]);
    if (z < down_z) {
      down_z = z;
      down = f;
    }
  }
  const double flat_tol = 1e-6 * m.bounding_radius;
  const double v_tol = 1e-3 * std::sqrt(m.gravity * m.bounding_radius);
  if (low <= flat_tol && m.max_friction < 0.999 * m.face_tip_ratio[down] && down_z < -0.999) {
    bool flat = true;
    for (int k = 0; k < 4 && flat; ++k) {
      const int v = m.face_vertices[down][k];
      const Vec3 r = s.R * m.vertices[v];
      flat = s.position.z() + r.z() - std::min(low, 0.0) <= flat_tol &&
             std::abs((s.velocity + s.omega.cross(r)).z()) <= v_tol;
    }
    if (flat) return down;
  }

  const int basin = quasi_static_down_face(m, s.R, tiebreak);
  if (energy < mg * m.face_escape[basin] * (1.0 - 1e-9)) return basin;
  return -1;
}

}  // namespace dicesim
