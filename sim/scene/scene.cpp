// Scene files: TOML -> (extends chain, --set overrides) -> one merged tree -> validated SceneDef.
// Defaults come from the member initialisers in scene.hpp; this file only reads what a scene states.
#include "sim/scene/scene.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "sim/scene/scene_error.hpp"
#include "sim/scene/scene_hash.hpp"
#include "sim/scene/scene_reader.hpp"

namespace dicesim {
namespace {

using namespace scene_detail;
namespace fs = std::filesystem;

// ---- Sections --------------------------------------------------------------------------------

void read_materials(Reader all, std::map<std::string, MaterialDef>& out) {
  if (!all.table()) return;
  for (const auto& [name, value] : *all.table()) {  // names are free: no finish() at this level
    Reader m(&value, all.path_of(name.str()), all.origin());
    if (!is_bare_key(name.str())) m.fail(&value, m.path(), "material names must match [A-Za-z0-9_-]+");
    MaterialDef def;
    def.density = m.number("density", kDensity, def.density);
    def.restitution = m.number("restitution", kRestitution, def.restitution);
    def.friction = m.number("friction", kFriction, def.friction);
    def.rolling_resistance = m.number("rolling_resistance", kRollingResistance, def.rolling_resistance);
    def.pivoting_resistance = m.number("pivoting_resistance", kPivotingResistance, def.pivoting_resistance);
    m.finish();
    out[std::string(name.str())] = def;
  }
}


constexpr Range kScale{.lo = 0, .hi = 1e6, .lo_open = true};
constexpr Range kCoordinate{.lo = -1e6, .hi = 1e6};  // times die.scale: metres
constexpr Names<bool, 2> kReadSides{{{"up", false}, {"down", true}}};  // value: read_down

constexpr bool is_preset(ShapeKind k) {
  return k == ShapeKind::D4 || k == ShapeKind::D6 || k == ShapeKind::D8 || k == ShapeKind::D10 ||
         k == ShapeKind::D12 || k == ShapeKind::D20;
}

// The OBJ file a mesh die names, read now (relative to the file the key was written in), so that
// the SceneDef alone describes the die.
void read_mesh_file(Reader& die, DieDef& def) {
  const toml::node* n = die.get("mesh");
  const fs::path written = n->as_string()->get();
  const fs::path base = n->source().path ? fs::path(*n->source().path).parent_path() : fs::current_path();
  const fs::path path = written.is_absolute() ? written : (base / written).lexically_normal();
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path))
    die.fail(n, die.path_of("mesh"), "cannot open mesh file '" + path.string() + "' (a Wavefront OBJ path relative to the scene file)");
  std::ostringstream text;
  text << in.rdbuf();
  def.mesh = written.string();
  def.mesh_path = path.string();
  def.mesh_text = text.str();
}

void read_die(Reader die, const std::map<std::string, MaterialDef>& materials, DieDef& def) {
  {
    const std::optional<std::string> name = die.string("shape");
    if (name) {
      const auto it = std::find(kShapeNames.begin(), kShapeNames.end(), *name);
      if (it == kShapeNames.end()) {
        std::string allowed;
        for (const char* k : kShapeNames) allowed += (allowed.empty() ? "" : ", ") + toml_string(k);
        die.fail(die.get("shape"), die.path_of("shape"), "must be one of: " + allowed);
      }
      def.shape = static_cast<ShapeKind>(it - kShapeNames.begin());
    }
  }
  const ShapeKind kind = def.shape;
  const std::string shape_text = std::string("shape = \"") + kShapeNames[static_cast<int>(kind)] + "\"";
  // A key that the shape does not use is an error, not silently ignored.
  auto only_for = [&](std::string_view key, bool applies, const char* which) {
    if (const toml::node* n = die.get(key); n && !applies)
      die.fail(n, die.path_of(key), "does not apply to " + shape_text + "; it is for " + which);
  };
  only_for("size", kind == ShapeKind::Box || is_preset(kind), "shape = \"box\" and the presets d4..d20");
  only_for("sides", kind == ShapeKind::Prism, "shape = \"prism\"");
  only_for("radius", kind == ShapeKind::Prism || kind == ShapeKind::Cylinder, "shape = \"prism\" and \"cylinder\"");
  only_for("height", kind == ShapeKind::Cylinder, "shape = \"cylinder\"");
  only_for("length", kind == ShapeKind::Prism, "shape = \"prism\"");
  only_for("vertices", kind == ShapeKind::Hull, "shape = \"hull\"");
  only_for("mesh", kind == ShapeKind::Mesh, "shape = \"mesh\"");
  only_for("scale", kind == ShapeKind::Hull || kind == ShapeKind::Mesh, "shape = \"hull\" and \"mesh\"");
  only_for("faces", kind == ShapeKind::Box || kind == ShapeKind::D6 || kind == ShapeKind::Cylinder,
           "shape = \"box\", \"d6\" and \"cylinder\"; use [[die.labels]]");
  only_for("labels", kind != ShapeKind::Cylinder, "polyhedral shapes; a cylinder's labels are [die.faces] heads, tails, edge");
  only_for("rounding", kind != ShapeKind::Mesh, "every shape but \"mesh\" (round the mesh itself)");

  if (kind == ShapeKind::Box) {
    def.size = die.vec3("size", kEdge, def.size, true);
  } else if (is_preset(kind)) {
    const toml::node* n = die.get("size");
    if (n && !(n->is_integer() || n->is_floating_point()))
      die.fail(n, die.path_of("size"), "must be a number for " + shape_text + ": the distance between opposite faces" +
                                           (kind == ShapeKind::D4 ? " (d4: from a face to the opposite vertex)" : "") +
                                           kEdge.text());
    def.size = Vec3::Constant(die.number("size", kEdge, def.size.x()));
  } else if (kind == ShapeKind::Prism) {
    def.sides = die.integer("sides", 3, 1000, def.sides);
    def.radius = die.number("radius", kEdge, def.radius);
    def.length = die.number("length", kEdge, def.length);
  } else if (kind == ShapeKind::Cylinder) {
    def.radius = die.number("radius", kEdge, def.radius);
    def.height = die.number("height", kEdge, def.height);
  } else if (kind == ShapeKind::Hull) {
    const toml::node* n = die.get("vertices");
    if (!n) die.fail_missing("vertices", "an array of at least 4 points [x, y, z] (m), not all in one plane");
    const auto* a = n->as_array();
    if (!a || a->size() < 4)
      die.fail(n, die.path_of("vertices"), "must be an array of at least 4 points [x, y, z] (m), not all in one plane");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string k = die.path_of("vertices") + "[" + std::to_string(i) + "]";
      const auto* p = a->get(i)->as_array();
      if (!p || p->size() != 3) die.fail(a->get(i), k, "must be an array of 3 numbers" + kCoordinate.text());
      Vec3 v;
      for (int c = 0; c < 3; ++c) v[c] = die.number(*p->get(c), k + "[" + std::to_string(c) + "]", kCoordinate);
      def.vertices.push_back(v);
    }
  } else if (kind == ShapeKind::Mesh) {
    if (!die.string("mesh")) die.fail_missing("mesh", "the path of a Wavefront OBJ file, relative to the scene file");
    read_mesh_file(die, def);
  }
  def.scale = die.number("scale", kScale, def.scale);
  def.rounding = die.number("rounding", kRounding, def.rounding);
  if (kind == ShapeKind::Cylinder && def.rounding >= std::min(def.radius, 0.5 * def.height))
    die.fail(die.get("rounding"), die.path_of("rounding"),
             "must be a number >= 0 and below min(radius, height/2) = " + num_text(std::min(def.radius, 0.5 * def.height)) + " m");
  if (die.get("read")) def.read_down = die.choice("read", kReadSides, false).second;

  def.base_material = material_ref(die, materials);
  for (Reader& label : die.tables("labels")) {
    LabelDef ld;
    ld.normal = label.direction("normal", ld.normal, true, "the face's outward direction");
    if (!label.get("label")) label.fail_missing("label", "an integer in [0, 999]");
    ld.label = label.integer("label", 0, 999, ld.label);
    label.finish();
    def.labels.push_back(ld);
  }
  for (Reader& region : die.tables("regions")) {
    RegionDef rd;
    rd.material = material_ref(region, materials);
    for (Reader& cut : region.tables("cuts")) {
      HalfSpace h;
      h.normal = cut.direction("normal", h.normal, true, "");
      h.offset = cut.number("offset", kLength, h.offset);
      cut.finish();
      rd.half_spaces.push_back(h);
    }
    region.finish();
    def.regions.push_back(std::move(rd));
  }

  Reader faces = die.sub("faces");
  if (kind == ShapeKind::Cylinder) {
    // Heads, tails, edge: any integers of the wire's range; equal labels group outcomes.
    for (std::size_t i = 0; i < 3; ++i)
      def.cylinder_labels[i] = faces.integer(kCylinderOutcomeNames[i], 0, 999, def.cylinder_labels[i]);
    faces.finish();
    die.finish();
    return;
  }
  for (std::size_t i = 0; i < 6; ++i) def.face_labels[i] = faces.integer(kFaceDirNames[i], 1, 99, def.face_labels[i]);
  for (std::size_t i = 0; i < 6; ++i)
    for (std::size_t j = i + 1; j < 6; ++j) {
      if (def.face_labels[i] != def.face_labels[j]) continue;
      // Blame the face the scene states (the other one may be a default).
      const std::size_t k = faces.get(kFaceDirNames[j]) ? j : i;
      faces.fail(faces.get(kFaceDirNames[k]), faces.path_of(kFaceDirNames[k]),
                 std::string("face labels must be distinct: ") + kFaceDirNames[i] + " and " + kFaceDirNames[j] +
                     " are both " + std::to_string(def.face_labels[i]));
    }
  faces.finish();
  die.finish();
}

void read_throw(Reader th, ThrowDef& def) {
  Reader orientation = th.sub("orientation");
  def.orientation.kind = orientation.choice("kind", kOrientationKinds, def.orientation.kind).second;
  def.orientation.euler_deg = orientation.vec3("euler_deg", kAngle, def.orientation.euler_deg, false);
  orientation.finish();

  Reader height = th.sub("height");
  const bool height_fixed = height.choice("kind", kHeightKinds, false).second;
  def.height.mean = height.number("mean", kLength, def.height.mean);
  def.height.sd = height.number("sd", kLengthSd, def.height.sd);
  if (height_fixed) def.height.sd = 0.0;
  height.finish();

  Reader velocity = th.sub("velocity");
  def.velocity.mean = velocity.vec3("mean", kSpeed, def.velocity.mean, true);
  def.velocity.sd = velocity.vec3("sd", kSpeedSd, def.velocity.sd, true);
  velocity.finish();

  Reader spin = th.sub("spin");
  const auto& [kind_name, kind] = spin.choice("kind", kSpinKinds, def.spin.kind);
  def.spin.kind = kind;
  if (kind == SpinKind::Normal) {
    def.spin.components.mean = spin.vec3("mean", kSpin, def.spin.components.mean, true);
    def.spin.components.sd = spin.vec3("sd", kSpinSd, def.spin.components.sd, true);
    if (kind_name == "fixed") def.spin.components.sd = Vec3::Zero();
  } else {
    def.spin.magnitude.mean = spin.number("mean", kSpin, def.spin.magnitude.mean);
    def.spin.magnitude.sd = spin.number("sd", kSpinSd, def.spin.magnitude.sd);
  }
  if (kind == SpinKind::BodyAxis) {
    def.spin.axis = spin.direction("axis", def.spin.axis, false, "the spin axis in the die's frame");
    def.spin.tilt_deg.mean = spin.number("tilt_deg", kAngle, def.spin.tilt_deg.mean);
    def.spin.tilt_deg.sd = spin.number("tilt_sd_deg", kTiltSd, def.spin.tilt_deg.sd);
  }
  spin.finish();

  if (th.get("catch_time")) {
    Reader ct = th.sub("catch_time");
    const bool fixed = ct.choice("kind", kHeightKinds, false).second;
    if (!ct.get("mean")) ct.fail_missing("mean", "a number" + kCatchTime.text());
    NormalScalar c;
    c.mean = ct.number("mean", kCatchTime, 0.5);
    c.sd = fixed ? 0.0 : ct.number("sd", kCatchTimeSd, 0.0);
    if (fixed && ct.get("sd")) ct.fail(ct.get("sd"), ct.path_of("sd"), "does not apply to kind = \"fixed\"");
    // A normal has unbounded support; 6 sd below the mean (probability 1e-9) must still be after release.
    if (c.mean - 6.0 * c.sd <= 0.0)
      ct.fail(ct.get("sd"), ct.path_of("sd"),
              "the catch time could be negative: sd must be below mean / 6 = " + num_text(c.mean / 6.0) + " s");
    ct.finish();
    def.catch_time = c;
  }
  if (th.get("hand")) def.hand = th.choice("hand", kHandKinds, def.hand).second;  // build(): only with [[dice]]
  th.finish();
}

void read_floor(Reader floor, FloorDef& def) {
  if (auto e = floor.number("restitution", kRestitution)) def.restitution = e;
  if (auto mu = floor.number("friction", kFriction)) def.friction = mu;
  floor.finish();
}

void read_sim(Reader sim, SimDef& def) {
  if (const std::optional<std::string> f = sim.string("fidelity")) {
    const std::optional<Fidelity> parsed = parse_fidelity(*f);
    if (!parsed) sim.fail(sim.get("fidelity"), sim.path_of("fidelity"), std::string("must be ") + kFidelityChoices);
    def.fidelity = *parsed;
  }
  def.gravity = sim.number("gravity", kGravity, def.gravity);
  def.stop_speed = sim.number("stop_speed", kStopSpeed, def.stop_speed);
  def.max_bounces = sim.integer("max_bounces", 1, 10'000'000, def.max_bounces);
  def.max_time = sim.number("max_time", kMaxTime, def.max_time);
  def.step = sim.number("step", kStep, def.step);
  def.contact_step = sim.number("contact_step", kStep, def.contact_step);
  def.contact_tol = sim.number("contact_tol", kContactTol, def.contact_tol);
  if (sim.get("end")) def.end = sim.choice("end", kEndKinds, def.end).second;
  sim.finish();
}

SceneDef build(const toml::table& tree, const std::string& origin, const std::string& default_name,
               std::vector<std::string>* dice_scene_texts) {
  SceneDef s = default_scene_def();
  s.sim.fidelity = Fidelity::Auto;  // a scene file that names no model gets the measured choice (issue 35)
  Reader top(&tree, "", origin);
  s.name = top.string("name").value_or(default_name);
  if (s.name.empty()) top.fail(top.get("name"), "name", "must be a non-empty string");
  top.get("extends");  // already resolved; listed so that it shows among the allowed keys
  read_materials(top.sub("materials"), s.materials);
  // [die] may be left out when every [[dice]] entry names a scene of its own.
  const bool has_die = top.get("die") != nullptr;
  const bool has_dice = tree.get("dice") != nullptr;
  if (has_die || !has_dice) read_die(top.sub("die"), s.materials, s.die);
  read_throw(top.sub("throw"), s.throw_);
  read_floor(top.sub("floor"), s.floor);
  read_sim(top.sub("sim"), s.sim);
  if (s.sim.end == EndKind::Catch && !s.throw_.catch_time) {
    Reader sim = top.sub("sim");
    sim.fail(sim.get("end"), "sim.end", "\"catch\" needs [throw.catch_time] (mean, sd in s: when the hand catches the die)");
  }
  if (s.sim.end == EndKind::Floor && s.throw_.catch_time) {
    Reader th = top.sub("throw");
    th.fail(th.get("catch_time"), "throw.catch_time", "applies only to sim.end = \"catch\"");
  }
  // Several dice and obstacles (issue 41), read last so that the allowed keys list them last.
  top.get("dice");
  if (has_dice) read_dice(top, s, has_die, dice_scene_texts);
  if (!has_dice) {
    Reader th = top.sub("throw");
    if (const toml::node* hand = th.get("hand"))
      th.fail(hand, "throw.hand", "applies only to a scene with [[dice]] (several dice)");
  }
  read_obstacles(top, s);
  if (!s.obstacles.empty() && s.dice.empty() && s.die.shape == ShapeKind::Cylinder) {
    Reader die = top.sub("die");
    die.fail(die.get("shape"), "die.shape",
             "a curved die (\"cylinder\") with [[obstacles]]: several dice and obstacles: polyhedral dice only");
  }
  if (top.get("outcomes")) {
    Reader outcomes = top.sub("outcomes");
    if (!has_dice)
      top.fail(top.get("outcomes"), "outcomes", "applies only to a scene with [[dice]] (several dice): one die's outcome is its face");
    s.outcomes.kind = outcomes.choice("kind", kOutcomeKinds, s.outcomes.kind).second;
    outcomes.finish();
  }
  top.finish();
  return s;
}

// ---- The merged tree: files, extends, overrides ----------------------------------------------

// Deep merge: tables merge key by key, anything else (arrays too) replaces. Nodes are moved, which
// keeps their source (file, line), so an error still names the file the value was written in.
void merge(toml::table& into, toml::table&& from) {
  for (auto&& [k, v] : from) {
    toml::node* dst = into.get(k.str());
    if (dst && dst->is_table() && v.is_table())
      merge(*dst->as_table(), std::move(*v.as_table()));
    else
      into.insert_or_assign(k, std::move(v));
  }
}

toml::table parse_toml(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, std::string_view(source));
  } catch (const toml::parse_error& e) {
    const auto& at = e.source().begin;
    throw SceneError(source, "", "", "TOML syntax error at line " + std::to_string(at.line) + ", column " +
                                         std::to_string(at.column) + ": " + std::string(e.description()));
  }
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path)) throw SceneError(path, "", "", "cannot open scene file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

struct ChainLink {
  fs::path id;     // canonical: what a cycle is detected on
  fs::path shown;  // as the user would write it
};

toml::table load_tree(const fs::path& path, std::vector<ChainLink>& chain);

// If `tree` extends another scene: that scene's tree (recursively) with `tree` merged on top.
// The base's `name` is dropped: a derived scene is named by its own file.
toml::table resolve_extends(toml::table tree, const std::string& file, const fs::path& dir, std::vector<ChainLink>& chain) {
  const toml::node* ext = tree.get("extends");
  if (!ext) return tree;
  if (!ext->is_string()) throw SceneError(file, "extends", describe(*ext), "must be a string: a scene path relative to this file");
  const fs::path base = (dir / ext->as_string()->get()).lexically_normal();
  if (!fs::is_regular_file(base))
    throw SceneError(file, "extends", describe(*ext), "cannot open scene file '" + base.string() + "'");
  const fs::path id = fs::weakly_canonical(base);
  for (const ChainLink& link : chain)
    if (link.id == id) {
      std::string cycle;
      for (const ChainLink& l : chain) cycle += l.shown.string() + " -> ";
      throw SceneError(file, "extends", describe(*ext), "extends cycle: " + cycle + base.string());
    }
  chain.push_back({id, base});
  toml::table merged = load_tree(base, chain);
  chain.pop_back();
  merged.erase("name");
  tree.erase("extends");
  merge(merged, std::move(tree));
  return merged;
}

toml::table load_tree(const fs::path& path, std::vector<ChainLink>& chain) {
  return resolve_extends(parse_toml(read_text(path.string()), path.string()), path.string(), path.parent_path(), chain);
}

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string_view::npos ? "" : std::string(s.substr(b, e - b + 1));
}

// `toml_key = VALUE` as a one-line TOML document with source "SCENE (--set)", so every node it holds
// carries that name into any error message. VALUE is TOML if it parses, else a bare string.
toml::table override_doc(const std::string& toml_key, const std::string& value, const std::string& source) {
  if (value.find_first_of("\r\n") == std::string::npos) {  // a newline could smuggle in more keys
    try {
      return toml::parse(toml_key + " = " + value, std::string_view(source));
    } catch (const toml::parse_error&) {
    }
  }
  return parse_toml(toml_key + " = " + toml_string(value), source);
}

const char* type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    default: return "a date or time";
  }
}

// One dotted segment of an override's key: a key, then the array indices after it ("cuts[0]").
struct KeyStep {
  std::string name;
  std::vector<std::size_t> indices;
};

// "a.b.c=VALUE", merged like one more file on top (missing tables are created). A key with indices,
// "die.regions[0].cuts[0].offset=VALUE", walks the merged tree instead: arrays of tables have no
// dotted form, and an index must name an element that is already there (a new one would be a
// region or cut with its other keys missing).
void apply_override(toml::table& tree, const std::string& text, const std::string& origin) {
  const std::string source = set_origin(origin);
  const auto eq = text.find('=');
  const std::string key = trim(text.substr(0, eq == std::string::npos ? text.size() : eq));
  auto bad = [&](const std::string& why) { return SceneError(source, key.empty() ? text : key, "", why); };
  if (eq == std::string::npos) throw bad("malformed override '" + text + "': expected KEY=VALUE, e.g. sim.stop_speed=0.05");
  const std::string malformed = "malformed override '" + text +
                                "': KEY must be a dotted key such as sim.stop_speed, each part optionally followed by "
                                "array indices such as die.regions[0]";

  std::vector<KeyStep> steps;
  std::size_t start = 0;
  for (std::size_t dot; start <= key.size(); start = dot + 1) {
    dot = std::min(key.find('.', start), key.size());
    std::string_view segment = std::string_view(key).substr(start, dot - start);
    KeyStep step;
    const auto bracket = segment.find('[');
    step.name = trim(segment.substr(0, bracket));
    if (step.name.empty()) throw bad(malformed);
    for (std::string_view rest = bracket == std::string_view::npos ? "" : segment.substr(bracket); !trim(rest).empty();) {
      rest = rest.substr(rest.find_first_not_of(" \t"));
      const auto close = rest.find(']');
      const std::string digits = rest.front() == '[' && close != std::string_view::npos ? trim(rest.substr(1, close - 1)) : "";
      std::size_t index = 0;
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), index);
      if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size()) throw bad(malformed);
      step.indices.push_back(index);
      rest = rest.substr(close + 1);
    }
    steps.push_back(std::move(step));
  }
  if (steps.front().name == "extends")
    throw bad("cannot be overridden: write a scene file that extends the other one");

  const std::string value = trim(std::string_view(text).substr(eq + 1));
  auto dotted = [&](std::size_t from) {
    std::string toml_key;
    for (std::size_t i = from; i < steps.size(); ++i) toml_key += (toml_key.empty() ? "" : ".") + toml_string(steps[i].name);
    return toml_key;
  };
  std::size_t last_indexed = steps.size();
  for (std::size_t i = 0; i < steps.size(); ++i)
    if (!steps[i].indices.empty()) last_indexed = i;
  if (last_indexed == steps.size()) {
    merge(tree, override_doc(dotted(0), value, source));
    return;
  }

  // Down to the last indexed element; everything on the way must exist.
  toml::node* at = &tree;
  std::string walked;  // the key so far, as the message names it
  for (std::size_t i = 0; i <= last_indexed; ++i) {
    const KeyStep& step = steps[i];
    toml::table* t = at->as_table();
    if (!t)
      throw bad(walked + " is " + type_name(*at) + ", not a table: it has no key '" + step.name + "'");
    walked = child_path(walked, step.name);
    at = t->get(step.name);
    if (!at) throw bad(walked + " is not in the scene: an indexed key can only name an element that exists");
    for (std::size_t k = 0; k < step.indices.size(); ++k) {
      const std::size_t index = step.indices[k];
      toml::array* a = at->as_array();
      if (!a) throw bad(walked + " is " + type_name(*at) + ", not an array: it cannot take the index [" + std::to_string(index) + "]");
      if (index >= a->size())
        throw bad("index " + std::to_string(index) + " is out of range: " + walked + " has " + std::to_string(a->size()) +
                  (a->size() == 1 ? " element" : " elements") +
                  (a->empty() ? "" : " (indices 0 to " + std::to_string(a->size() - 1) + ")"));
      walked += "[" + std::to_string(index) + "]";
      if (i == last_indexed && k + 1 == step.indices.size() && last_indexed + 1 == steps.size()) {
        // The key ends in an index: that element is replaced.
        toml::table doc = override_doc("v", value, source);
        a->replace(a->cbegin() + static_cast<std::ptrdiff_t>(index), std::move(*doc.get("v")));
        return;
      }
      at = a->get(index);
    }
  }
  toml::table* element = at->as_table();
  if (!element)
    throw bad(walked + " is " + type_name(*at) + ", not a table: it has no key '" + steps[last_indexed + 1].name + "'");
  merge(*element, override_doc(dotted(last_indexed + 1), value, source));
}

std::string stem_or(const std::string& path, const std::string& fallback) {
  const std::string stem = fs::path(path).stem().string();
  return stem.empty() ? fallback : stem;
}


// The resolved tree's hash (scene_hash.hpp); build() validates it and reads a mesh's OBJ. A [[dice]]
// entry's `scene` path is replaced by "sha256:" and the hash of that scene's own canonical text (as
// a mesh's path by its OBJ's): an edited die scene changes the hash, the same one under another
// path does not.
std::string tree_sha256(toml::table tree, const std::string& origin, const std::vector<std::string>& overrides) {
  for (const std::string& o : overrides) apply_override(tree, o, origin);
  std::vector<std::string> dice_texts;
  const SceneDef def = build(tree, origin, stem_or(origin, "scene"), &dice_texts);
  if (toml::array* dice = tree.get("dice") ? tree.get("dice")->as_array() : nullptr)
    for (std::size_t i = 0; i < dice_texts.size() && i < dice->size(); ++i)
      if (!dice_texts[i].empty()) dice->get(i)->as_table()->insert_or_assign("scene", "sha256:" + sha256_hex(dice_texts[i]));
  return sha256_hex(canonical_scene_text(tree, def.die.mesh_text));
}

SceneDef finish_tree(toml::table tree, const std::string& origin, const std::vector<std::string>& overrides) {
  for (const std::string& o : overrides) apply_override(tree, o, origin);
  return build(tree, origin, stem_or(origin, "scene"), nullptr);
}

}  // namespace

namespace scene_detail {

// A [[dice]] entry's `scene`, read now (relative to the file the key was written in, with its own
// `extends`) and validated as a scene of its own; only its [die] and [materials] are used. A scene
// with [[dice]] cannot be named (no nesting, and so no cycle through `scene`).
DieSource load_die_scene(Reader& entry) {
  const toml::node* n = entry.get("scene");
  const std::string key = entry.path_of("scene");
  const fs::path written = n->as_string()->get();
  const fs::path base = n->source().path ? fs::path(*n->source().path).parent_path() : fs::current_path();
  const fs::path path = written.is_absolute() ? written : (base / written).lexically_normal();
  if (!fs::is_regular_file(path))
    entry.fail(n, key, "cannot open scene file '" + path.string() + "' (a scene path relative to the scene file that states the key)");
  std::vector<ChainLink> chain{{fs::weakly_canonical(path), path}};
  toml::table tree = load_tree(path, chain);
  if (tree.get("dice"))
    entry.fail(n, key, "names a scene with [[dice]]: a [[dice]] entry's scene must be a scene of one die (its [die])");
  SceneDef def = build(tree, path.string(), stem_or(path.string(), "scene"), nullptr);
  std::string text = canonical_scene_text(tree, def.die.mesh_text);
  return {std::move(def.die), std::move(def.materials), std::move(text)};
}

}  // namespace scene_detail

SceneDef default_scene_def() { return SceneDef{}; }

SceneDef load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  std::vector<ChainLink> chain;
  if (fs::is_regular_file(path)) chain.push_back({fs::weakly_canonical(path), fs::path(path)});
  return finish_tree(load_tree(path, chain), path, overrides);
}

SceneDef parse_scene(const std::string& toml_text, const std::string& origin, const std::vector<std::string>& overrides) {
  std::vector<ChainLink> chain;
  toml::table tree = resolve_extends(parse_toml(toml_text, origin), origin, fs::current_path(), chain);
  return finish_tree(std::move(tree), origin, overrides);
}

std::string scene_sha256(const std::string& path, const std::vector<std::string>& overrides) {
  std::vector<ChainLink> chain;
  if (fs::is_regular_file(path)) chain.push_back({fs::weakly_canonical(path), fs::path(path)});
  return tree_sha256(load_tree(path, chain), path, overrides);
}

std::string scene_text_sha256(const std::string& toml_text, const std::string& origin, const std::vector<std::string>& overrides) {
  std::vector<ChainLink> chain;
  return tree_sha256(resolve_extends(parse_toml(toml_text, origin), origin, fs::current_path(), chain), origin, overrides);
}

}  // namespace dicesim
