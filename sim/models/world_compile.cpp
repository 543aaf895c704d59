// compile() for a scene with several dice or obstacles: each die compiled alone, the obstacles'
// pieces and materials, and the toss's outcomes (tuples or sums of the dice's).
#include "sim/models/world_compile.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <string>

#include "sim/body/world.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {

namespace {

// Unit edge directions of a die's core, one per parallel class (the narrow phase's overlap axes).
std::vector<Vec3> edge_directions(const DieModel& d) {
  std::vector<Vec3> dirs;
  for (int f = 0; f < d.face_count(); ++f) {
    const auto loop = d.face_vertices(f);
    for (std::size_t k = 0; k < loop.size(); ++k) {
      Vec3 e = d.vertices[static_cast<std::size_t>(loop[(k + 1) % loop.size()])] -
               d.vertices[static_cast<std::size_t>(loop[k])];
      if (e.norm() == 0.0) continue;
      e.normalize();
      const bool seen = std::any_of(dirs.begin(), dirs.end(), [&](const Vec3& o) { return std::abs(o.dot(e)) > 1.0 - 1e-12; });
      if (!seen) dirs.push_back(e);
    }
  }
  return dirs;
}

double mean(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()); }

int digits(int label) {
  int d = 1;
  for (int x = std::abs(label); x >= 10; x /= 10) ++d;
  return d;
}

// The toss's outcomes from the dice's: labels ascending, and each tuple's outcome.
void build_world_outcomes(World& w, DieModel& m, const std::string& origin) {
  const int n = w.size();
  w.stride.assign(static_cast<std::size_t>(n), 1);
  long long tuples = 1;
  for (int k = n - 1; k >= 0; --k) {
    w.stride[static_cast<std::size_t>(k)] = static_cast<int>(tuples);
    tuples *= w.dice[static_cast<std::size_t>(k)].outcomes();
  }
  if (tuples > 1'000'000)
    throw SceneError(origin, "dice", std::to_string(tuples) + " tuples", "at most 10^6 tuples of outcomes");
  std::vector<int> per(static_cast<std::size_t>(n));
  const auto labels_of = [&](long long t) {
    for (int k = 0; k < n; ++k) {
      const DieModel& d = w.dice[static_cast<std::size_t>(k)];
      per[static_cast<std::size_t>(k)] = d.outcome_labels[static_cast<std::size_t>((t / w.stride[static_cast<std::size_t>(k)]) % d.outcomes())];
    }
  };
  w.tuple_outcome.assign(static_cast<std::size_t>(tuples), 0);
  m.outcome_labels.clear();
  if (w.kind == OutcomeKind::Sum) {
    std::map<int, int> sums;
    for (long long t = 0; t < tuples; ++t) {
      labels_of(t);
      sums[std::accumulate(per.begin(), per.end(), 0)] = 0;
    }
    int i = 0;
    for (auto& [sum, index] : sums) {
      index = i++;
      m.outcome_labels.push_back(sum);
    }
    for (long long t = 0; t < tuples; ++t) {
      labels_of(t);
      w.tuple_outcome[static_cast<std::size_t>(t)] = sums[std::accumulate(per.begin(), per.end(), 0)];
    }
  } else {
    // A tuple's label: the dice's labels side by side in decimal, each in as many digits as the
    // largest label has (2d6: 11 .. 66; a d6 and a d20: 0101 .. 0620), the first die first, so
    // that ascending labels are the tuples in order.
    int width = 1;
    for (const DieModel& d : w.dice)
      for (int l : d.outcome_labels) {
        if (l < 0) throw SceneError(origin, "dice", std::to_string(l), "tuple outcomes need labels >= 0");
        width = std::max(width, digits(l));
      }
    if (width * n > 9)
      throw SceneError(origin, "outcomes.kind", "\"tuple\"",
                       "these dice's tuples need " + std::to_string(width * n) +
                           " digits, more than a label holds (9): use kind = \"sum\"");
    long long base = 1;
    for (int i = 0; i < width; ++i) base *= 10;
    for (long long t = 0; t < tuples; ++t) {
      labels_of(t);
      long long label = 0;
      for (int l : per) label = label * base + l;
      w.tuple_outcome[static_cast<std::size_t>(t)] = static_cast<int>(t);
      m.outcome_labels.push_back(static_cast<int>(label));
    }
  }
  w.faces_per_outcome.assign(m.outcome_labels.size(), 0);
  for (long long t = 0; t < tuples; ++t) {
    long long faces = 1;
    for (int k = 0; k < n; ++k) {
      const DieModel& d = w.dice[static_cast<std::size_t>(k)];
      const int o = static_cast<int>((t / w.stride[static_cast<std::size_t>(k)]) % d.outcomes());
      faces *= std::count(d.face_outcome.begin(), d.face_outcome.end(), o);
    }
    w.faces_per_outcome[static_cast<std::size_t>(w.tuple_outcome[static_cast<std::size_t>(t)])] += static_cast<int>(faces);
  }
  // Faces no longer map to the toss's outcomes: the first die's faces read -1 (a world toss
  // reports outcomes only), and no two outcomes are alike by design.
  std::fill(m.face_outcome.begin(), m.face_outcome.end(), -1);
  m.outcome_alike.resize(m.outcome_labels.size());
  std::iota(m.outcome_alike.begin(), m.outcome_alike.end(), 0);
  m.symmetry_rotations = 1;
  m.alike_note = "several dice: outcomes are tuples or sums, none grouped by symmetry";
}

}  // namespace

DieModel compile_world(const SceneDef& scene, const std::string& origin) {
  auto w = std::make_shared<World>();
  std::vector<DiceEntryDef> entries = scene.dice;
  if (entries.empty()) {  // one die among obstacles
    DiceEntryDef one;
    one.die = scene.die;
    one.materials = scene.materials;
    entries.push_back(one);
  }
  if (static_cast<int>(entries.size()) > 6)
    throw SceneError(origin, "dice", std::to_string(entries.size()) + " dice", "at most 6 dice in one toss");
  const Fidelity f = scene.sim.fidelity;
  if (f == Fidelity::Paper || f == Fidelity::Stepped)
    throw SceneError(origin, "sim.fidelity", std::string("\"") + to_string(f) + "\"",
                     "several dice and obstacles run in \"impulse\" (or \"auto\"; \"static\" for dice without obstacles)");
  if (f == Fidelity::Static && !scene.obstacles.empty())
    throw SceneError(origin, "sim.fidelity", "\"static\"", "\"static\" has no motion, so no obstacle could matter: use \"impulse\"");
  if (scene.sim.end == EndKind::Catch)
    throw SceneError(origin, "sim.end", "\"catch\"", "several dice and obstacles end on the floor");

  w->hand = scene.throw_.hand;
  w->kind = scene.outcomes.kind;
  for (const DiceEntryDef& e : entries) {
    SceneDef one = scene;
    one.dice.clear();
    one.obstacles.clear();
    one.die = e.die;
    for (const auto& [name, mat] : e.materials) one.materials[name] = mat;
    DieModel d = compile(one, origin);
    if (d.curved())
      throw SceneError(origin, "dice", e.scene.empty() ? "die" : e.scene, "several dice and obstacles: polyhedral dice only");
    w->die_edges.push_back(edge_directions(d));
    w->die_restitution.push_back(mean(d.vertex_restitution));
    w->die_friction.push_back(mean(d.vertex_friction));
    w->offsets.push_back(e.offset);
    w->die_width.push_back(2.0 * *std::min_element(d.face_height.begin(), d.face_height.end()));
    w->dice.push_back(std::move(d));
  }

  w->pieces = obstacle_pieces(scene);
  std::vector<std::pair<double, double>> materials;  // (restitution, friction) of the pieces, distinct
  for (const ObstaclePiece& p : w->pieces) {
    const std::pair<double, double> mat{p.restitution, p.friction};
    auto it = std::find(materials.begin(), materials.end(), mat);
    if (it == materials.end()) it = materials.insert(materials.end(), mat);
    w->piece_material.push_back(static_cast<int>(it - materials.begin()));
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    if (!p.plane) {
      lo = hi = p.corners.front();
      for (const Vec3& x : p.corners) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
    }
    double width = std::numeric_limits<double>::infinity();
    for (const Vec3& nf : p.face_normals) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const Vec3& x : p.corners) lo = std::min(lo, nf.dot(x)), hi = std::max(hi, nf.dot(x));
      if (!p.plane) width = std::min(width, hi - lo);
    }
    w->piece_lo.push_back(lo);
    w->piece_hi.push_back(hi);
    w->piece_width.push_back(width);
  }
  std::vector<int> polyhedra;
  for (std::size_t p = 0; p < w->pieces.size(); ++p)
    if (!w->pieces[p].plane) polyhedra.push_back(static_cast<int>(p));
  w->piece_tree = PieceTree(w->piece_lo, w->piece_hi, polyhedra);
  for (std::size_t p = 0; p < w->pieces.size(); ++p)
    if (w->pieces[p].plane) w->plane_pieces.push_back(static_cast<int>(p));
  // Die i against die j held at rest (world_toss.cpp): the two dice's mean restitution and friction.
  const std::size_t n = w->dice.size();
  w->die_pair_material.assign(n, std::vector<int>(n, -1));
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const std::pair<double, double> mat{0.5 * (w->die_restitution[i] + w->die_restitution[j]),
                                          0.5 * (w->die_friction[i] + w->die_friction[j])};
      auto it = std::find(materials.begin(), materials.end(), mat);
      if (it == materials.end()) it = materials.insert(materials.end(), mat);
      w->die_pair_material[i][j] = static_cast<int>(it - materials.begin());
    }
  for (const DieModel& d : w->dice) {
    std::vector<DieModel> against;
    for (const auto& [e, mu] : materials) {
      DieModel a = d;
      std::fill(a.vertex_restitution.begin(), a.vertex_restitution.end(), e);
      std::fill(a.vertex_friction.begin(), a.vertex_friction.end(), mu);
      a.max_friction = mu;
      against.push_back(std::move(a));
    }
    w->die_against.push_back(std::move(against));
  }

  DieModel m = w->dice.front();
  m.name = scene.name;
  build_world_outcomes(*w, m, origin);
  if (f == Fidelity::Auto)
    m.fidelity_reason = "auto: `impulse`: several dice or obstacles, which only `impulse` strikes against each other";
  m.world = std::move(w);
  return m;
}

}  // namespace dicesim
