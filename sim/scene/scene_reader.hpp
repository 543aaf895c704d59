// Internal to sim/scene's .cpp files (scene.cpp, scene_world.cpp, key_unit.cpp): how keys and values
// are shown in errors, the ranges every number is checked against, and Reader, which reads one TOML
// table with validation. Include it nowhere else.
#pragma once

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim::scene_detail {
// The source name of every value that came from an override: the scene it overrides, marked.
inline std::string set_origin(const std::string& scene) { return scene + " (--set)"; }

// ---- Showing keys and values in error messages ------------------------------------------------

// A TOML basic string, so that any text (also a bare --set value) round-trips through the parser.
inline std::string toml_string(std::string_view s) {
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

inline bool is_bare_key(std::string_view k) {
  if (k.empty()) return false;
  for (char c : k)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

// Face keys read alike ("+x", "-x") when a leading '-' is quoted too, which TOML allows.
inline std::string key_text(std::string_view k) {
  return is_bare_key(k) && k.front() != '-' ? std::string(k) : toml_string(k);
}

inline std::string child_path(const std::string& parent, std::string_view key) {
  return parent.empty() ? key_text(key) : parent + "." + key_text(key);
}

// The value as the user wrote it (TOML syntax), for "key = value" in messages.
inline std::string describe(const toml::node& n) {
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
inline std::string num_text(double v) {
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
constexpr Range kRounding{.lo = 0, .hi = 100, .hi_open = true, .unit = "m"};

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

// A material name that must be defined under [materials].
inline std::string material_ref(Reader& r, const std::map<std::string, MaterialDef>& materials) {
  std::string defined;
  for (const auto& [name, m] : materials) defined += (defined.empty() ? "" : ", ") + name;
  if (defined.empty()) defined = "(none)";
  const std::optional<std::string> name = r.string("material");
  if (!name) r.fail_missing("material", "the name of a material; defined: " + defined);
  if (!materials.count(*name)) r.fail(r.get("material"), r.path_of("material"), "must name a material in [materials]; defined: " + defined);
  return *name;
}

// ---- Several dice and obstacles (scene_world.cpp) ----------------------------------------------

// A [[dice]] entry's `scene`: that scene's die and materials, and its canonical text (the hash).
struct DieSource {
  DieDef die;
  std::map<std::string, MaterialDef> materials;
  std::string canonical_text;
};
// Defined in scene.cpp, beside the files it reads.
DieSource load_die_scene(Reader& entry);

// [[dice]] into s.dice (has_die: the scene states [die]; dice_scene_texts, if given, gets each
// named die scene's canonical text for the hash) and [[obstacles]] into s.obstacles.
void read_dice(Reader& top, SceneDef& s, bool has_die, std::vector<std::string>* dice_scene_texts);
void read_obstacles(Reader& top, SceneDef& s);

}  // namespace dicesim::scene_detail
