// Scene files: TOML -> (extends chain, --set overrides) -> one merged tree -> validated SceneDef.
// Defaults come from the member initialisers in scene.hpp; this file only reads what a scene states.
#include "sim/scene/scene.hpp"
#include "sim/scene/key_unit.hpp"

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

#include <Eigen/Eigenvalues>
#include <toml++/toml.h>

#include "sim/scene/scene_error.hpp"
#include "sim/scene/scene_hash.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;
// The source name of every value that came from an override: the scene it overrides, marked.
std::string set_origin(const std::string& scene) { return scene + " (--set)"; }

// ---- Showing keys and values in error messages ------------------------------------------------

// A TOML basic string, so that any text (also a bare --set value) round-trips through the parser.
std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04X", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + '"';
}

bool is_bare_key(std::string_view k) {
  if (k.empty()) return false;
  for (char c : k)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

// Face keys read alike ("+x", "-x") when a leading '-' is quoted too, which TOML allows.
std::string key_text(std::string_view k) {
  return is_bare_key(k) && k.front() != '-' ? std::string(k) : toml_string(k);
}

std::string child_path(const std::string& parent, std::string_view key) {
  return parent.empty() ? key_text(key) : parent + "." + key_text(key);
}

// The value as the user wrote it (TOML syntax), for "key = value" in messages.
std::string describe(const toml::node& n) {
  if (const auto* s = n.as_string()) return toml_string(s->get());
  std::string out;
  if (const auto* a = n.as_array()) {
    for (const auto& e : *a) out += (out.empty() ? "" : ", ") + describe(e);
    return "[" + out + "]";
  }
  if (const auto* t = n.as_table()) {
    for (const auto& [k, v] : *t) out += (out.empty() ? "" : ", ") + key_text(k.str()) + " = " + describe(v);
    return "{" + out + "}";
  }
  if (const auto* f = n.as_floating_point()) {
    // Shortest text that reads back as the same double (0.03, not 0.029999999999999999).
    char buf[64];
    std::string s(buf, std::to_chars(buf, buf + sizeof buf, f->get()).ptr);
    if (std::isfinite(f->get()) && s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
  }
  std::ostringstream os;
  n.visit([&](const auto& v) { os << v; });
  return os.str();
}

// 1e6 rather than 1e+06: ranges in messages read like the README.
std::string num_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  std::string s = buf;
  if (auto e = s.find("e+"); e != std::string::npos) {
    s.erase(e + 1, 1);
    while (s.size() > e + 2 && s[e + 1] == '0') s.erase(e + 1, 1);
  }
  return s;
}

// The closed or open interval a number must lie in, and its unit, as the message shows it.
struct Range {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;
  const char* unit = "";

  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  bool bounded() const { return std::isfinite(lo) || std::isfinite(hi); }
  // Follows "must be a number": " in (0, 1e6] kg/m^3", " >= 0 m/s", " (deg)" or "".
  std::string text() const {
    if (!bounded()) return *unit ? std::string(" (") + unit + ")" : "";
    std::string s;
    if (std::isfinite(lo) && std::isfinite(hi))
      s = std::string(" in ") + (lo_open ? "(" : "[") + num_text(lo) + ", " + num_text(hi) + (hi_open ? ")" : "]");
    else if (std::isfinite(lo))
      s = std::string(lo_open ? " > " : " >= ") + num_text(lo);
    else
      s = std::string(hi_open ? " < " : " <= ") + num_text(hi);
    return *unit ? s + " " + unit : s;
  }
};

constexpr Range kDensity{.lo = 0, .hi = 1e6, .lo_open = true, .unit = "kg/m^3"};
constexpr Range kRestitution{.lo = 0, .hi = 1};
constexpr Range kFriction{.lo = 0, .hi = 10};
constexpr Range kEdge{.lo = 0, .hi = 100, .lo_open = true, .unit = "m"};
constexpr Range kLength{.unit = "m"};
constexpr Range kLengthSd{.lo = 0, .unit = "m"};
constexpr Range kSpeed{.unit = "m/s"};
constexpr Range kSpeedSd{.lo = 0, .unit = "m/s"};
constexpr Range kSpin{.unit = "rad/s"};
constexpr Range kSpinSd{.lo = 0, .unit = "rad/s"};
constexpr Range kAngle{.unit = "deg"};
constexpr Range kGravity{.lo = 0, .hi = 1000, .lo_open = true, .unit = "m/s^2"};
constexpr Range kStopSpeed{.lo = 0, .hi = 100, .unit = "m/s"};
constexpr Range kMaxTime{.lo = 0, .hi = 1e6, .lo_open = true, .unit = "s"};
constexpr Range kStep{.lo = 1e-7, .hi = 1e-2, .unit = "s"};
constexpr Range kContactTol{.lo = 0.0, .hi = 1e-2, .unit = ""};
constexpr Range kAnyNumber{};

// Names a key may take, and what each means.
template <class T, std::size_t N>
using Names = std::array<std::pair<std::string_view, T>, N>;

constexpr Names<OrientationKind, 3> kOrientationKinds{{
    {"uniform", OrientationKind::Uniform},
    {"euler-uniform", OrientationKind::EulerUniform},
    {"fixed", OrientationKind::Fixed},
}};
// "fixed" spin is the normal kind with sd 0: the sampler needs no extra case.
constexpr Names<SpinKind, 5> kSpinKinds{{
    {"normal", SpinKind::Normal},
    {"random-axis", SpinKind::RandomAxis},
    {"octant-axis", SpinKind::OctantAxis},
    {"body-axis", SpinKind::BodyAxis},
    {"fixed", SpinKind::Normal},
}};
constexpr Names<EndKind, 2> kEndKinds{{{"floor", EndKind::Floor}, {"catch", EndKind::Catch}}};
constexpr Range kRollingResistance{.lo = 0, .hi = 0.1, .unit = "m"};
constexpr Range kPivotingResistance{.lo = 0, .hi = 0.1, .unit = "m"};
constexpr Range kCatchTime{.lo = 0, .hi = 1e3, .lo_open = true, .unit = "s"};
constexpr Range kCatchTimeSd{.lo = 0, .hi = 1e3, .unit = "s"};
constexpr Range kTiltSd{.lo = 0, .hi = 180, .unit = "deg"};
constexpr Names<bool, 2> kHeightKinds{{{"normal", false}, {"fixed", true}}};  // value: is fixed
constexpr Names<HandKind, 2> kHandKinds{{{"each", HandKind::Each}, {"shared", HandKind::Shared}}};
constexpr Names<OutcomeKind, 2> kOutcomeKinds{{{"tuple", OutcomeKind::Tuple}, {"sum", OutcomeKind::Sum}}};
// Several dice and obstacles (issue 41).
constexpr Range kOffset{.lo = -1, .hi = 1, .unit = "m"};  // and |offset| <= 1 m
constexpr Range kPosition{.lo = -1e6, .hi = 1e6, .unit = "m"};
constexpr Range kYaw{.lo = -3600, .hi = 3600, .unit = "deg"};
constexpr Range kBaffleAngle{.lo = 0, .hi = 90, .lo_open = true, .hi_open = true, .unit = "deg"};
constexpr Range kBaffleReach{.lo = 0, .hi = 1, .lo_open = true};
constexpr int kMinDice = 2, kMaxDice = 6;

// ---- Reading one table -----------------------------------------------------------------------

// Reads the keys of one TOML table with validation. Every key asked for becomes a known key
// (whether present or not), so finish() can name the allowed keys without a second list.
class Reader {
 public:
  // `node` may be absent (all defaults); when present it must be a table.
  Reader(const toml::node* node, std::string path, const std::string& origin)
      : path_(std::move(path)), origin_(&origin) {
    if (node && !(table_ = node->as_table())) fail(node, path_, "must be a table");
  }

  const std::string& path() const { return path_; }
  const std::string& origin() const { return *origin_; }
  const toml::table* table() const { return table_; }
  std::string path_of(std::string_view key) const { return child_path(path_, key); }

  // The node under `key`, or nullptr.
  const toml::node* get(std::string_view key) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
    return table_ ? table_->get(key) : nullptr;
  }

  Reader sub(std::string_view key) { return Reader(get(key), path_of(key), *origin_); }

  // Errors name the file the value was written in: this scene, a scene it extends, or "SCENE (--set)".
  [[noreturn]] void fail(const toml::node* n, const std::string& key, const std::string& allowed) const {
    const std::string file = n && n->source().path ? *n->source().path : *origin_;
    throw SceneError(file, key, n ? describe(*n) : "", allowed);
  }
  // A required key is absent: blame the file of the table that lacks it.
  [[noreturn]] void fail_missing(std::string_view key, const std::string& allowed) const {
    const bool known = table_ && table_->source().path;
    throw SceneError(known ? *table_->source().path : *origin_, path_of(key), "", "required: " + allowed);
  }

  double number(const toml::node& n, const std::string& key, const Range& r) const {
    const std::optional<double> v = n.is_integer() || n.is_floating_point() ? n.value<double>() : std::nullopt;
    if (!v) fail(&n, key, "must be a number" + r.text());
    if (!std::isfinite(*v)) fail(&n, key, "must be finite: a number" + r.text());
    if (!r.contains(*v)) fail(&n, key, "must be a number" + r.text());
    return *v;
  }

  std::optional<double> number(std::string_view key, const Range& r) {
    const toml::node* n = get(key);
    return n ? std::optional(number(*n, path_of(key), r)) : std::nullopt;
  }
  double number(std::string_view key, const Range& r, double fallback) {
    return number(key, r).value_or(fallback);
  }

  // Three numbers; `scalar_ok`: a single number stands for all three.
  Vec3 vec3(std::string_view key, const Range& r, const Vec3& fallback, bool scalar_ok) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const std::string k = path_of(key);
    if (scalar_ok && (n->is_integer() || n->is_floating_point())) return Vec3::Constant(number(*n, k, r));
    const auto* a = n->as_array();
    if (!a || a->size() != 3)
      fail(n, k, std::string(scalar_ok ? "must be a number or an array of 3 numbers" : "must be an array of 3 numbers") +
                     (r.bounded() ? ", each" + r.text() : r.text()));
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = number(*a->get(i), k + "[" + std::to_string(i) + "]", r);
    return v;
  }

  // A direction: an array of 3 numbers, not all 0 (`meaning`: what it is, for the message).
  Vec3 direction(std::string_view key, const Vec3& fallback, bool required, const std::string& meaning) {
    const toml::node* n = get(key);
    const std::string allowed = "an array of 3 numbers, not all 0" + (meaning.empty() ? "" : ": " + meaning);
    if (!n && required) fail_missing(key, allowed);
    const Vec3 v = vec3(key, kAnyNumber, fallback, false);
    if (v.isZero(0.0)) fail(n, path_of(key), "must be " + allowed);
    return v;
  }

  std::optional<std::string> string(std::string_view key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_string()) fail(n, path_of(key), "must be a string");
    return n->as_string()->get();
  }

  int integer(std::string_view key, long long lo, long long hi, int fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const std::string range = " in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!n->is_integer()) fail(n, path_of(key), "must be an integer" + range);
    const long long v = n->as_integer()->get();
    if (v < lo || v > hi) fail(n, path_of(key), "must be an integer" + range);
    return static_cast<int>(v);
  }

  // One of `names`; the entry of `fallback` when the key is absent.
  template <class T, std::size_t N>
  const std::pair<std::string_view, T>& choice(std::string_view key, const Names<T, N>& names, T fallback) {
    const std::optional<std::string> s = string(key);
    for (const auto& entry : names)
      if (s ? entry.first == *s : entry.second == fallback) return entry;
    std::string allowed;
    for (const auto& entry : names) allowed += (allowed.empty() ? "" : ", ") + toml_string(entry.first);
    allowed = "must be one of: " + allowed;
    fail(get(key), path_of(key), allowed);
  }

  // Elements of the array of tables under `key` (e.g. [[die.regions]]), each as a Reader.
  std::vector<Reader> tables(std::string_view key) {
    const toml::node* n = get(key);
    std::vector<Reader> out;
    if (!n) return out;
    const auto* a = n->as_array();
    if (!a) fail(n, path_of(key), "must be an array of tables");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string k = path_of(key) + "[" + std::to_string(i) + "]";
      if (!a->get(i)->is_table()) fail(a->get(i), k, "must be a table");
      out.emplace_back(a->get(i), k, *origin_);
    }
    return out;
  }

  // Typos must not pass silently: every key present must be one that was asked for.
  void finish() const {
    if (!table_) return;
    for (const auto& [k, v] : *table_) {
      if (std::find(known_.begin(), known_.end(), k.str()) != known_.end()) continue;
      std::string allowed;
      for (const auto& a : known_) allowed += (allowed.empty() ? "" : ", ") + key_text(a);
      const std::string where = path_.empty() ? "at the top level" : "in [" + path_ + "]";
      fail(&v, path_of(k.str()), "unknown key '" + std::string(k.str()) + "' " + where + "; allowed: " + allowed);
    }
  }

 private:
  const toml::table* table_ = nullptr;
  std::string path_;
  const std::string* origin_;
  std::vector<std::string> known_;
};

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

// A material name that must be defined under [materials].
std::string material_ref(Reader& r, const std::map<std::string, MaterialDef>& materials) {
  std::string defined;
  for (const auto& [name, m] : materials) defined += (defined.empty() ? "" : ", ") + name;
  if (defined.empty()) defined = "(none)";
  const std::optional<std::string> name = r.string("material");
  if (!name) r.fail_missing("material", "the name of a material; defined: " + defined);
  if (!materials.count(*name)) r.fail(r.get("material"), r.path_of("material"), "must name a material in [materials]; defined: " + defined);
  return *name;
}

constexpr Range kScale{.lo = 0, .hi = 1e6, .lo_open = true};
constexpr Range kRounding{.lo = 0, .hi = 100, .hi_open = true, .unit = "m"};
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

// ---- Several dice and obstacles (issue 41) ----------------------------------------------------

// A [[dice]] entry's `scene`: that scene's die and materials, and its canonical text (the hash).
struct DieSource {
  DieDef die;
  std::map<std::string, MaterialDef> materials;
  std::string canonical_text;
};
DieSource load_die_scene(Reader& entry);  // below, beside the files it reads

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

namespace dicesim {

std::string key_unit(std::string_view key) {
  // The key without indices, and any material's name as "*": "materials.*.density".
  std::string k;
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (key[i] == '[') {
      while (i < key.size() && key[i] != ']') ++i;
      continue;
    }
    k += key[i];
  }
  if (k.rfind("materials.", 0) == 0) {
    const std::size_t dot = k.find('.', 10);
    if (dot != std::string::npos) k = "materials.*" + k.substr(dot);
  }
  static const std::pair<std::string_view, const Range*> units[] = {
      {"materials.*.density", &kDensity},
      {"materials.*.rolling_resistance", &kRollingResistance},
      {"materials.*.pivoting_resistance", &kPivotingResistance},
      {"die.size", &kEdge},
      {"die.radius", &kEdge},
      {"die.length", &kEdge},
      {"die.height", &kEdge},
      {"die.rounding", &kRounding},
      {"die.regions.cuts.offset", &kLength},
      {"throw.orientation.euler_deg", &kAngle},
      {"throw.height.mean", &kLength},
      {"throw.height.sd", &kLengthSd},
      {"throw.velocity.mean", &kSpeed},
      {"throw.velocity.sd", &kSpeedSd},
      {"throw.spin.mean", &kSpin},
      {"throw.spin.sd", &kSpinSd},
      {"throw.spin.tilt_deg", &kAngle},
      {"throw.spin.tilt_sd_deg", &kTiltSd},
      {"throw.catch_time.mean", &kCatchTime},
      {"throw.catch_time.sd", &kCatchTimeSd},
      {"sim.gravity", &kGravity},
      {"sim.stop_speed", &kStopSpeed},
      {"sim.max_time", &kMaxTime},
      {"sim.step", &kStep},
      {"sim.contact_step", &kStep},
      {"sim.contact_tol", &kContactTol},
      {"dice.offset", &kOffset},
      {"obstacles.point", &kPosition},
      {"obstacles.vertices", &kPosition},
      {"obstacles.centre", &kPosition},
      {"obstacles.size", &kEdge},
      {"obstacles.yaw_deg", &kYaw},
      {"obstacles.thickness", &kEdge},
      {"obstacles.width", &kEdge},
      {"obstacles.height", &kEdge},
      {"obstacles.radius", &kEdge},
      {"obstacles.pyramid_base", &kEdge},
      {"obstacles.pyramid_height", &kEdge},
      {"obstacles.pyramid_pitch", &kEdge},
      {"obstacles.baffle_angle_deg", &kBaffleAngle},
      {"obstacles.exit_height", &kEdge},
  };
  for (const auto& [name, range] : units)
    if (k == name) return range->unit;
  return "";
}

}  // namespace dicesim
