#include "sim/body/obstacles.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sim/body/hull.hpp"
#include "sim/body/shape.hpp"

namespace dicesim {
namespace {

constexpr double kParallelTol = 1e-9;  // two unit edge directions with |a x b| below this are one class

// A convex polyhedron piece from its corners and faces (index loops, either orientation): each
// face's normal from its loop (Newell), turned outward (away from the corners' centroid).
ObstaclePiece convex_piece(std::vector<Vec3> corners, const std::vector<std::vector<int>>& faces) {
  ObstaclePiece p;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& c : corners) centroid += c;
  centroid /= static_cast<double>(corners.size());
  for (const std::vector<int>& f : faces) {
    Vec3 n = Vec3::Zero();
    for (std::size_t k = 0; k < f.size(); ++k) n += corners[f[k]].cross(corners[f[(k + 1) % f.size()]]);
    n.normalize();
    if (n.dot(corners[f[0]] - centroid) < 0.0) n = -n;
    p.face_normals.push_back(n);
    p.face_points.push_back(corners[f[0]]);
    for (std::size_t k = 0; k < f.size(); ++k) {
      const Vec3 d = (corners[f[(k + 1) % f.size()]] - corners[f[k]]).normalized();
      bool known = false;
      for (const Vec3& e : p.edge_dirs) known = known || e.cross(d).norm() <= kParallelTol;
      if (!known) p.edge_dirs.push_back(d);
    }
  }
  p.corners = std::move(corners);
  return p;
}

// A box of edge lengths `size` (local axes: the columns of `axes`) centred at `centre`.
ObstaclePiece box_piece(const Vec3& centre, const Mat3& axes, const Vec3& size) {
  const ConvexShape b = box_shape(size);
  std::vector<Vec3> corners;
  for (const Vec3& v : b.vertices) corners.push_back(centre + axes * v);
  return convex_piece(std::move(corners), b.faces);
}

// A square pyramid: base square of edge `base` centred at `at` on the plane through it normal to
// `out` (unit), with edges along `u` and out x u; apex `height` along `out`.
ObstaclePiece pyramid_piece(const Vec3& at, const Vec3& out, const Vec3& u, double base, double height) {
  const Vec3 v = out.cross(u);
  const double h = 0.5 * base;
  std::vector<Vec3> corners = {at - h * u - h * v, at + h * u - h * v, at + h * u + h * v, at - h * u + h * v,
                               at + height * out};
  return convex_piece(std::move(corners), {{0, 1, 2, 3}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}});
}

ObstaclePiece hull_piece(const std::vector<Vec3>& points) {
  const ConvexShape h = convex_hull(points);
  return convex_piece(h.vertices, h.faces);
}

}  // namespace

std::vector<ObstaclePiece> obstacle_pieces(const SceneDef& s) {
  std::vector<ObstaclePiece> out;
  for (std::size_t i = 0; i < s.obstacles.size(); ++i) {
    const ObstacleDef& o = s.obstacles[i];
    const std::string prefix = "obstacles[" + std::to_string(i) + "] " + kObstacleKindNames[static_cast<int>(o.kind)];
    const Mat3 yaw = rot_z(o.yaw_deg * kPi / 180.0);
    const std::size_t first = out.size();
    // A box given in the obstacle's local frame (origin at `centre`, before the yaw).
    auto local_box = [&](const Vec3& c, const Vec3& size, const std::string& name, const Mat3& axes = Mat3::Identity()) {
      out.push_back(box_piece(o.centre + yaw * c, yaw * axes, size));
      out.back().name = prefix + " " + name;
    };
    const double t = o.thickness;
    switch (o.kind) {
      case ObstacleKind::Plane: {
        ObstaclePiece p;
        p.plane = true;
        p.normal = o.normal.normalized();
        p.offset = p.normal.dot(o.point);
        p.name = prefix;
        out.push_back(std::move(p));
        break;
      }
      case ObstacleKind::Polyhedron:
        out.push_back(hull_piece(o.vertices));
        out.back().name = prefix;
        break;
      case ObstacleKind::Box:
        out.push_back(box_piece(o.centre, yaw, o.size));
        out.back().name = prefix;
        break;
      case ObstacleKind::Tray: {
        const double lx = o.size.x(), wy = o.size.y(), h = o.size.z();
        local_box(Vec3(0.5 * (lx + t), 0, 0.5 * h), Vec3(t, wy + 2 * t, h), "wall +x");
        local_box(Vec3(-0.5 * (lx + t), 0, 0.5 * h), Vec3(t, wy + 2 * t, h), "wall -x");
        local_box(Vec3(0, 0.5 * (wy + t), 0.5 * h), Vec3(lx, t, h), "wall +y");
        local_box(Vec3(0, -0.5 * (wy + t), 0.5 * h), Vec3(lx, t, h), "wall -y");
        break;
      }
      case ObstacleKind::Backboard: {
        const double w = o.width, h = o.height, b = o.pyramid_base, pitch = o.pyramid_pitch;
        local_box(Vec3(0.5 * t, 0, 0.5 * h), Vec3(t, w, h), "board");
        // As many as fit, centred; the small slack keeps an exact fit (w = b + k pitch) from losing one.
        const int ny = static_cast<int>(std::floor((w - b) / pitch + 1e-9)) + 1;
        const int nz = static_cast<int>(std::floor((h - b) / pitch + 1e-9)) + 1;
        const Vec3 out_dir = yaw * Vec3(-1, 0, 0), along = yaw * Vec3(0, 1, 0);
        for (int r = 0; r < nz; ++r)
          for (int c = 0; c < ny; ++c) {
            const Vec3 at(0, (c - 0.5 * (ny - 1)) * pitch, 0.5 * h + (r - 0.5 * (nz - 1)) * pitch);
            out.push_back(pyramid_piece(o.centre + yaw * at, out_dir, along, b, o.pyramid_height));
            out.back().name = prefix + " pyramid row " + std::to_string(r) + " column " + std::to_string(c);
          }
        break;
      }
      case ObstacleKind::Tower: {
        const double wx = o.size.x(), wy = o.size.y(), h = o.size.z(), e = o.exit_height;
        local_box(Vec3(-0.5 * (wx + t), 0, 0.5 * h), Vec3(t, wy + 2 * t, h), "wall -x");
        local_box(Vec3(0.5 * (wx + t), 0, 0.5 * (e + h)), Vec3(t, wy + 2 * t, h - e), "wall +x (above the exit)");
        local_box(Vec3(0, 0.5 * (wy + t), 0.5 * h), Vec3(wx, t, h), "wall +y");
        local_box(Vec3(0, -0.5 * (wy + t), 0.5 * h), Vec3(wx, t, h), "wall -y");
        // Baffle k (from the bottom) hangs from wall -x (k even) or +x (k odd) with its upper end at
        // drop + (k + 1/2) gap and slopes down by `drop` over its reach toward the other wall: the
        // baffles' heights split the chute evenly, half a gap left above the top one and below the
        // bottom one's lower end.
        const double a = o.baffle_angle_deg * kPi / 180.0;
        const double reach = o.baffle_reach * wx, drop = reach * std::tan(a), len = reach / std::cos(a);
        const double gap = o.baffles > 0 ? (h - drop) / o.baffles : 0.0;
        for (int k = 0; k < o.baffles; ++k) {
          const double side = k % 2 == 0 ? -1.0 : 1.0;  // the wall it hangs from
          const Vec3 upper(side * 0.5 * wx, 0, drop + (k + 0.5) * gap);
          const Vec3 lower = upper + Vec3(-side * reach, 0, -drop);
          Mat3 axes;
          axes.col(0) = (lower - upper) / len;  // along the slope
          axes.col(1) = Vec3::UnitY();
          axes.col(2) = axes.col(0).cross(axes.col(1));
          local_box(0.5 * (upper + lower), Vec3(len, wy, t), "baffle " + std::to_string(k), axes);
        }
        break;
      }
      case ObstacleKind::Cup: {
        const int n = o.sides;
        const double r = o.radius, h = o.height;
        const double length = 2.0 * (r + t) * std::tan(kPi / n);  // the outer polygon's edge: the ring is closed
        for (int j = 0; j < n; ++j) {
          const double phi = 2.0 * kPi * j / n;
          Mat3 axes;
          axes.col(0) = Vec3(std::cos(phi), std::sin(phi), 0);  // radial, outward
          axes.col(1) = Vec3::UnitZ().cross(axes.col(0));
          axes.col(2) = Vec3::UnitZ();
          local_box((r + 0.5 * t) * axes.col(0) + Vec3(0, 0, 0.5 * h), Vec3(t, length, h), "wall " + std::to_string(j), axes);
        }
        break;
      }
    }
    const MaterialDef& m = s.materials.at(o.material);
    for (std::size_t k = first; k < out.size(); ++k) {
      out[k].restitution = m.restitution;
      out[k].friction = m.friction;
      out[k].material = o.material;
    }
  }
  return out;
}

}  // namespace dicesim
