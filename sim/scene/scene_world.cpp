// Scene files, the keys of several dice and obstacles: [[dice]] (each entry's die, from this scene or
// another), [[obstacles]] (planes, polyhedra and the compositions' parameters) and their checks.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "sim/scene/scene_reader.hpp"

namespace dicesim::scene_detail {

bool same_material(const MaterialDef& a, const MaterialDef& b) {
  return a.density == b.density && a.restitution == b.restitution && a.friction == b.friction &&
         a.rolling_resistance == b.rolling_resistance && a.pivoting_resistance == b.pivoting_resistance;
}

// `dice_scene_texts` (when given): per entry, the canonical text of the scene it names ("" for this
// scene's own [die]).
void read_dice(Reader& top, SceneDef& s, bool has_die, std::vector<std::string>* dice_scene_texts) {
  const toml::node* node = top.get("dice");
  std::vector<Reader> entries = top.tables("dice");
  if (entries.size() < static_cast<std::size_t>(kMinDice) || entries.size() > static_cast<std::size_t>(kMaxDice)) {
    const std::string file = node->source().path ? *node->source().path : top.origin();
    const std::string count = std::to_string(entries.size()) + (entries.size() == 1 ? " entry" : " entries");
    throw SceneError(file, "dice", count,
                     "must have " + std::to_string(kMinDice) + " to " + std::to_string(kMaxDice) + " entries" +
                         (entries.size() == 1 ? " (one die: use [die] and leave out [[dice]])" : ""));
  }
  for (std::size_t i = 0; i < entries.size(); ++i) {
    Reader& e = entries[i];
    DiceEntryDef d;
    d.scene = e.string("scene").value_or("");
    std::string text;
    if (d.scene.empty()) {
      if (!has_die)
        e.fail_missing("scene", "the path of a scene file whose [die] this die is (this scene has no [die] for the entry to use)");
      d.die = s.die;
      d.materials = s.materials;
      if (d.die.shape == ShapeKind::Cylinder) {
        Reader die = top.sub("die");
        die.fail(die.get("shape"), "die.shape",
                 "a curved die (\"cylinder\") cannot be one of [[dice]]: several dice and obstacles: polyhedral dice only");
      }
    } else {
      DieSource src = load_die_scene(e);
      if (src.die.shape == ShapeKind::Cylinder)
        e.fail(e.get("scene"), e.path_of("scene"),
               "names a curved die (shape = \"cylinder\"): several dice and obstacles: polyhedral dice only");
      d.die = std::move(src.die);
      d.materials = std::move(src.materials);
      text = std::move(src.canonical_text);
    }
    d.offset = e.vec3("offset", kOffset, d.offset, false);
    if (d.offset.norm() > 1.0)
      e.fail(e.get("offset"), e.path_of("offset"),
             "must be an array of 3 numbers (m) of length at most 1 m; its length is " + num_text(d.offset.norm()) + " m");
    e.finish();
    s.dice.push_back(std::move(d));
    if (dice_scene_texts) dice_scene_texts->push_back(std::move(text));
  }
  if (has_die) return;
  // No [die]: the first entry's die stands for the scene's die, with its materials.
  s.die = s.dice.front().die;
  for (const auto& [name, m] : s.dice.front().materials) {
    const auto [it, fresh] = s.materials.emplace(name, m);
    if (!fresh && !same_material(it->second, m))
      entries.front().fail(entries.front().get("scene"), entries.front().path_of("scene"),
                           "this scene has no [die], so the first entry's die stands for it, and that die's scene "
                           "defines material '" + name + "' unlike this scene's [materials." + name +
                               "]: rename one of them");
  }
}

// The points span a solid: their spread about the centroid has a third direction, at least 1e-6 of
// the largest (the hull's tolerance, sim/body/hull.hpp, measured the same relative way).
bool spans_solid(const std::vector<Vec3>& points) {
  if (points.size() < 4) return false;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : points) c += p;
  c /= static_cast<double>(points.size());
  Mat3 spread = Mat3::Zero();
  for (const Vec3& p : points) spread += (p - c) * (p - c).transpose();
  const Vec3 var = Eigen::SelfAdjointEigenSolver<Mat3>(spread, Eigen::EigenvaluesOnly).eigenvalues();  // ascending
  return var.z() > 0.0 && std::sqrt(std::max(0.0, var.x()) / var.z()) > 1e-6;
}

void read_obstacle(Reader& o, const std::map<std::string, MaterialDef>& materials, ObstacleDef& def) {
  {
    const toml::node* n = o.get("kind");
    std::string allowed;
    for (const char* k : kObstacleKindNames) allowed += (allowed.empty() ? "" : ", ") + toml_string(k);
    if (!n) o.fail_missing("kind", "one of: " + allowed);
    const std::string name = o.string("kind").value_or("");
    const auto it = std::find(kObstacleKindNames.begin(), kObstacleKindNames.end(), name);
    if (it == kObstacleKindNames.end()) o.fail(n, o.path_of("kind"), "must be one of: " + allowed);
    def.kind = static_cast<ObstacleKind>(it - kObstacleKindNames.begin());
  }
  const ObstacleKind kind = def.kind;
  using K = ObstacleKind;
  const std::string kind_text = std::string("kind = \"") + kObstacleKindNames[static_cast<int>(kind)] + "\"";
  // A key the kind does not use is an error, not silently ignored.
  auto only_for = [&](std::string_view key, std::initializer_list<K> kinds) {
    const toml::node* n = o.get(key);
    if (!n || std::find(kinds.begin(), kinds.end(), kind) != kinds.end()) return;
    std::string which;
    for (K k : kinds) which += (which.empty() ? "" : ", ") + toml_string(kObstacleKindNames[static_cast<int>(k)]);
    o.fail(n, o.path_of(key), "does not apply to " + kind_text + "; it is for kind " + which);
  };
  only_for("point", {K::Plane});
  only_for("normal", {K::Plane});
  only_for("vertices", {K::Polyhedron});
  only_for("centre", {K::Box, K::Tray, K::Backboard, K::Tower, K::Cup});
  only_for("size", {K::Box, K::Tray, K::Tower});
  only_for("yaw_deg", {K::Box, K::Tray, K::Backboard, K::Tower, K::Cup});
  only_for("thickness", {K::Tray, K::Backboard, K::Tower, K::Cup});
  only_for("width", {K::Backboard});
  only_for("height", {K::Backboard, K::Cup});
  only_for("pyramid_base", {K::Backboard});
  only_for("pyramid_height", {K::Backboard});
  only_for("pyramid_pitch", {K::Backboard});
  only_for("baffles", {K::Tower});
  only_for("baffle_angle_deg", {K::Tower});
  only_for("baffle_reach", {K::Tower});
  only_for("exit_height", {K::Tower});
  only_for("radius", {K::Cup});
  only_for("sides", {K::Cup});

  def.material = material_ref(o, materials);
  auto required = [&](std::string_view key, const std::string& what) {
    if (!o.get(key)) o.fail_missing(key, what + " (" + kind_text + ")");
  };
  const std::string size_text = "an array of 3 numbers, each" + kEdge.text();
  switch (kind) {
    case K::Plane:
      def.point = o.vec3("point", kPosition, def.point, false);
      def.normal = o.direction("normal", def.normal, true, "the wall's normal, out of the solid into the free space").normalized();
      break;
    case K::Polyhedron: {
      const toml::node* n = o.get("vertices");
      const std::string allowed = "an array of at least 4 points [x, y, z] (m), not all in one plane";
      if (!n) o.fail_missing("vertices", allowed);
      const auto* a = n->as_array();
      if (!a || a->size() < 4) o.fail(n, o.path_of("vertices"), "must be " + allowed);
      for (std::size_t i = 0; i < a->size(); ++i) {
        const std::string k = o.path_of("vertices") + "[" + std::to_string(i) + "]";
        const auto* p = a->get(i)->as_array();
        if (!p || p->size() != 3) o.fail(a->get(i), k, "must be an array of 3 numbers" + kPosition.text());
        Vec3 v;
        for (int c = 0; c < 3; ++c) v[c] = o.number(*p->get(c), k + "[" + std::to_string(c) + "]", kPosition);
        def.vertices.push_back(v);
      }
      if (!spans_solid(def.vertices))
        o.fail(n, o.path_of("vertices"), "must be " + allowed + " (these lie in one plane, on one line or at one point)");
      break;
    }
    case K::Box:
    case K::Tray:
    case K::Tower:
      required("size", kind == K::Box ? "edge lengths: " + size_text
                       : kind == K::Tray ? "inner length (x), inner width (y), wall height (z): " + size_text
                                         : "the chute's inner x width, inner y width, height: " + size_text);
      def.size = o.vec3("size", kEdge, def.size, false);
      break;
    case K::Backboard:
      required("width", "the wall's length along its face, a number" + kEdge.text());
      def.width = o.number("width", kEdge, def.width);
      def.height = o.number("height", kEdge, def.height);
      def.pyramid_base = o.number("pyramid_base", kEdge, def.pyramid_base);
      def.pyramid_height = o.number("pyramid_height", kEdge, def.pyramid_height);
      def.pyramid_pitch = o.number("pyramid_pitch", kEdge, def.pyramid_pitch);
      if (def.pyramid_base > std::min(def.width, def.height))
        o.fail(o.get("pyramid_base"), o.path_of("pyramid_base"),
               "must be a number in (0, min(width, height)] = (0, " + num_text(std::min(def.width, def.height)) +
                   "] m: at least one pyramid must fit on the face");
      if (def.pyramid_pitch < def.pyramid_base)
        o.fail(o.get("pyramid_pitch"), o.path_of("pyramid_pitch"),
               "must be a number >= pyramid_base = " + num_text(def.pyramid_base) + " m (the pyramids must not overlap)");
      break;
    case K::Cup:
      required("radius", "the inner radius (centre to each wall's inner face), a number" + kEdge.text());
      required("height", "the wall height, a number" + kEdge.text());
      def.radius = o.number("radius", kEdge, def.radius);
      def.height = o.number("height", kEdge, def.height);
      def.sides = o.integer("sides", 3, 360, def.sides);
      break;
  }
  if (kind != K::Plane && kind != K::Polyhedron) {
    def.centre = o.vec3("centre", kPosition, def.centre, false);
    def.yaw_deg = o.number("yaw_deg", kYaw, def.yaw_deg);
  }
  if (kind == K::Tray || kind == K::Backboard || kind == K::Tower || kind == K::Cup)
    def.thickness = o.number("thickness", kEdge, def.thickness);
  if (kind == K::Tower) {
    def.baffles = o.integer("baffles", 0, 20, def.baffles);
    def.baffle_angle_deg = o.number("baffle_angle_deg", kBaffleAngle, def.baffle_angle_deg);
    def.baffle_reach = o.number("baffle_reach", kBaffleReach, def.baffle_reach);
    def.exit_height = o.number("exit_height", kEdge, def.size.z() / 4.0);
    if (def.exit_height >= def.size.z())
      o.fail(o.get("exit_height"), o.path_of("exit_height"),
             "must be a number in (0, size.z) = (0, " + num_text(def.size.z()) + ") m: the exit is in the tower's foot");
    const double drop = def.baffle_reach * def.size.x() * std::tan(def.baffle_angle_deg * kPi / 180.0);
    if (def.baffles > 0 && drop >= def.size.z()) {
      const char* key = o.get("baffle_angle_deg") ? "baffle_angle_deg" : o.get("baffle_reach") ? "baffle_reach" : "size";
      o.fail(o.get(key), o.path_of(key),
             "the baffles do not fit: each drops baffle_reach * size.x * tan(baffle_angle_deg) = " + num_text(drop) +
                 " m, which must be below the tower's height size.z = " + num_text(def.size.z()) + " m");
    }
  }
  o.finish();
}

void read_obstacles(Reader& top, SceneDef& s) {
  std::vector<Reader> entries = top.tables("obstacles");
  for (Reader& o : entries) {
    ObstacleDef def;
    read_obstacle(o, s.materials, def);
    s.obstacles.push_back(std::move(def));
  }
}

}  // namespace dicesim::scene_detail
