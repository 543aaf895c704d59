#include "messages/run_spec.hpp"
#include "messages/spec_scene.hpp"
#include "sim/scene/scene_hash.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "messages/wire.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim::wire {
namespace fs = std::filesystem;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in || fs::is_directory(p)) throw SceneError(p.string(), "", "", "cannot open scene file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The `extends` value of a scene text, if it has one that is a string (errors are left to
// load_scene, which reports them with the right file and key).
std::string extends_of(const std::string& text) {
  try {
    const toml::table t = toml::parse(text);
    if (auto v = t["extends"].value<std::string>()) return *v;
  } catch (const toml::parse_error&) {
  }
  return {};
}

struct Fnv {
  std::uint64_t h = 1469598103934665603ULL;
  void bytes(const void* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ULL;
  }
  void str(const std::string& s) {
    u64(s.size());
    bytes(s.data(), s.size());
  }
  void u64(std::uint64_t v) { bytes(&v, sizeof v); }
  void d(double v) { bytes(&v, sizeof v); }
  void vec(const Vec3& v) {
    for (int i = 0; i < 3; ++i) d(v[i]);
  }
};

bool is_mesh_override(const std::string& o) {
  const std::size_t eq = o.find('=');
  if (eq == std::string::npos) return false;
  std::string key = o.substr(0, eq);
  key.erase(0, key.find_first_not_of(" \t"));
  key.erase(key.find_last_not_of(" \t") + 1);
  return key == "die.mesh";
}

// A TOML basic string holding `s` (a path).
std::string toml_quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

}  // namespace

std::vector<SceneFile> read_scene_files(const std::string& path, const std::vector<std::string>& asset_paths,
                                        std::vector<SceneFile>* assets) {
  // Follow the extends chain as load_scene does (relative to each file's folder), at most 64 deep
  // (load_scene itself reports cycles).
  std::vector<fs::path> chain{fs::path(path)};
  std::vector<std::string> texts{read_file(path)};
  for (int depth = 0; depth < 64; ++depth) {
    const std::string ext = extends_of(texts.back());
    if (ext.empty()) break;
    const fs::path base = (chain.back().parent_path() / ext).lexically_normal();
    if (!fs::is_regular_file(base)) break;  // load_scene names the error
    chain.push_back(base);
    texts.push_back(read_file(base));
  }
  const std::size_t n_scene = chain.size();
  for (const std::string& a : asset_paths) {
    chain.push_back(fs::path(a));
    texts.push_back(read_file(a));
  }
  // Paths relative to the common ancestor of every file, so that the relative `extends` (and mesh
  // path) of each resolves the same way inside the worker's temporary copy.
  std::vector<fs::path> abs;
  for (const fs::path& p : chain) abs.push_back(fs::weakly_canonical(fs::absolute(p)));
  fs::path root = abs[0].parent_path();
  for (const fs::path& p : abs)
    while (!root.empty() && std::mismatch(root.begin(), root.end(), p.begin(), p.end()).first != root.end())
      root = root.parent_path();
  std::vector<SceneFile> files;
  for (std::size_t i = 0; i < abs.size(); ++i) {
    SceneFile f{fs::relative(abs[i], root).generic_string(), texts[i]};
    if (i < n_scene) files.push_back(std::move(f));
    else if (assets) assets->push_back(std::move(f));
  }
  return files;
}

void check_wire_outcomes(const DieModel& m, const std::string& origin) {
  std::vector<std::int32_t> labels(m.outcome_labels.begin(), m.outcome_labels.end());
  if (valid_outcome_labels(labels)) return;
  const auto [lo, hi] = std::minmax_element(m.outcome_labels.begin(), m.outcome_labels.end());
  throw SceneError(origin, "die", std::to_string(m.outcomes()) + " outcomes" +
                                      (m.outcome_labels.empty() ? std::string()
                                                                : ", labels " + std::to_string(*lo) + ".." + std::to_string(*hi)),
                   "distributed runs (run, aggregate, sweep --workers) carry 1 to " + std::to_string(kMaxOutcomes) +
                       " outcomes with labels in [0, " + std::to_string(kMaxLabel) +
                       "]: group faces with [[die.labels]], or use `dicesim toss`");
}

std::string scene_hash(const std::vector<SceneFile>& files, const std::vector<std::string>& overrides) {
  Fnv f;
  for (const SceneFile& s : files) {
    f.str(s.path);
    f.str(s.text);
  }
  for (const std::string& o : overrides) f.str(o);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(f.h));
  return hex;
}

std::uint64_t model_fingerprint(const DieModel& m) {
  Fnv f;
  for (const Vec3& v : m.vertices) f.vec(v);
  for (const Vec3& v : m.face_normals) f.vec(v);
  for (int l : m.face_labels) f.u64(static_cast<std::uint64_t>(l));
  for (int l : m.outcome_labels) f.u64(static_cast<std::uint64_t>(l));
  f.u64(m.read_down);
  f.d(m.rounding);
  for (double r : m.vertex_restitution) f.d(r);
  for (double r : m.vertex_friction) f.d(r);
  f.d(m.bounding_radius);
  f.d(m.mass);
  f.vec(m.principal_moments);
  for (int i = 0; i < 9; ++i) f.d(m.geo_to_body.data()[i]);
  f.u64(m.symmetric_top);
  f.u64(static_cast<std::uint64_t>(m.fidelity));
  f.d(m.gravity);
  f.d(m.stop_speed);
  f.u64(static_cast<std::uint64_t>(m.max_bounces));
  f.d(m.max_time);
  const ThrowDef& t = m.throw_;
  f.u64(static_cast<std::uint64_t>(t.orientation.kind));
  f.vec(t.orientation.euler_deg);
  f.d(t.height.mean);
  f.d(t.height.sd);
  f.vec(t.velocity.mean);
  f.vec(t.velocity.sd);
  f.u64(static_cast<std::uint64_t>(t.spin.kind));
  f.vec(t.spin.components.mean);
  f.vec(t.spin.components.sd);
  f.d(t.spin.magnitude.mean);
  f.d(t.spin.magnitude.sd);
  return f.h;
}

namespace {
// Writes the run's files into a private temporary directory, calls f(the main scene's path there,
// the overrides) and removes the directory.
template <class F>
auto in_spec_dir(const RunSpec& spec, F&& f) {
  if (spec.files.empty()) throw SceneError(spec.origin, "", "", "run_start carries no scene file");
  std::vector<SceneFile> all = spec.files;
  all.insert(all.end(), spec.assets.begin(), spec.assets.end());
  for (const SceneFile& s : all) {
    const fs::path p(s.path);
    if (p.empty() || p.is_absolute())
      throw SceneError(spec.origin, "", s.path, "run_start file paths must be relative");
    for (const auto& part : p)
      if (part == "..") throw SceneError(spec.origin, "", s.path, "run_start file paths must stay inside their root");
  }
  char tmpl[] = "/tmp/dicesim-run-XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error(std::string("mkdtemp: ") + std::strerror(errno));
  const fs::path dir(tmpl);
  struct Cleanup {
    fs::path d;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } cleanup{dir};
  for (const SceneFile& s : all) {
    const fs::path p = dir / s.path;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << s.text;
  }
  // A mesh named by --set die.mesh=PATH was relative to the user's folder: it is the asset here.
  std::vector<std::string> overrides = spec.overrides;
  for (std::string& o : overrides)
    if (is_mesh_override(o) && !spec.assets.empty()) o = "die.mesh=" + toml_quoted((dir / spec.assets.back().path).string());
  // The scene's name comes from the file's stem, as in `toss`; errors name the user's path.
  const fs::path main = dir / spec.files[0].path;
  return f(main.string(), overrides);
}
}  // namespace

DieModel compile_spec(const RunSpec& spec) {
  return compile(in_spec_dir(spec, [](const std::string& path, const std::vector<std::string>& o) { return load_scene(path, o); }),
                 spec.origin);
}

void with_spec_files(const RunSpec& spec, const std::function<void(const std::string&, const std::vector<std::string>&)>& f) {
  in_spec_dir(spec, [&](const std::string& path, const std::vector<std::string>& o) {
    f(path, o);
    return 0;
  });
}

std::string spec_scene_sha256(const RunSpec& spec) {
  return in_spec_dir(spec, [](const std::string& path, const std::vector<std::string>& o) { return scene_sha256(path, o); });
}

RunSpec make_run_spec(std::int64_t run_id, const std::string& scene_path, const std::vector<std::string>& overrides,
                      const DieModel& model, std::uint64_t seed, std::uint64_t total, int trace_every) {
  RunSpec spec;
  spec.run_id = run_id;
  spec.origin = scene_path;
  spec.overrides = overrides;
  spec.fidelity = to_string(model.fidelity);
  spec.seed = seed;
  spec.total = total;
  spec.trace_every = trace_every;
  spec.fingerprint = model_fingerprint(model);
  check_wire_outcomes(model, scene_path);
  spec.labels = model.outcome_labels;
  // A mesh die reads an OBJ file: it travels in run_start with the scene files.
  const SceneDef def = load_scene(scene_path, overrides);
  std::vector<std::string> asset_paths;
  if (!def.die.mesh_path.empty()) asset_paths.push_back(def.die.mesh_path);
  spec.files = read_scene_files(scene_path, asset_paths, &spec.assets);
  std::vector<SceneFile> hashed = spec.files;
  hashed.insert(hashed.end(), spec.assets.begin(), spec.assets.end());
  spec.hash = scene_hash(hashed, overrides);
  // What a worker will do with run_start, done here first: a run no worker could rebuild fails now.
  if (model_fingerprint(compile_spec(spec)) != spec.fingerprint)
    throw std::runtime_error("the scene does not rebuild identically from its files (run_start)");
  return spec;
}

std::int64_t new_run_id() {
  std::random_device rd;
  std::uint64_t v = 0;
  while (v == 0) v = ((std::uint64_t{rd()} << 32) ^ rd()) & INT64_MAX;
  return static_cast<std::int64_t>(v);
}

dicesim_lcm::run_start to_message(const RunSpec& spec) {
  dicesim_lcm::run_start m;
  m.utime = now_utime();
  m.run_id = spec.run_id;
  m.origin = spec.origin;
  m.scene_path = spec.files.empty() ? "" : spec.files[0].path;
  m.scene_text = spec.files.empty() ? "" : spec.files[0].text;
  for (std::size_t i = 1; i < spec.files.size(); ++i) {
    m.base_paths.push_back(spec.files[i].path);
    m.base_texts.push_back(spec.files[i].text);
  }
  m.n_bases = static_cast<std::int32_t>(m.base_paths.size());
  m.overrides = spec.overrides;
  m.n_overrides = static_cast<std::int32_t>(m.overrides.size());
  m.scene_hash = spec.hash;
  m.model_fingerprint = static_cast<std::int64_t>(spec.fingerprint);
  m.fidelity = spec.fidelity;
  m.seed = static_cast<std::int64_t>(spec.seed);
  m.total_tosses = static_cast<std::int64_t>(spec.total);
  m.trace_every = spec.trace_every;
  m.outcome_labels.assign(spec.labels.begin(), spec.labels.end());
  m.n_outcomes = static_cast<std::int32_t>(m.outcome_labels.size());
  for (const SceneFile& a : spec.assets) {
    m.asset_paths.push_back(a.path);
    m.asset_texts.push_back(a.text);
  }
  m.n_assets = static_cast<std::int32_t>(m.asset_paths.size());
  return m;
}

RunSpec from_message(const dicesim_lcm::run_start& m) {
  RunSpec s;
  s.run_id = m.run_id;
  s.origin = m.origin;
  s.files.push_back({m.scene_path, m.scene_text});
  for (std::size_t i = 0; i < m.base_paths.size() && i < m.base_texts.size(); ++i)
    s.files.push_back({m.base_paths[i], m.base_texts[i]});
  s.overrides = m.overrides;
  s.fidelity = m.fidelity;
  s.seed = static_cast<std::uint64_t>(m.seed);
  s.total = m.total_tosses > 0 ? static_cast<std::uint64_t>(m.total_tosses) : 0;
  s.trace_every = m.trace_every;
  s.fingerprint = static_cast<std::uint64_t>(m.model_fingerprint);
  s.hash = m.scene_hash;
  s.labels.assign(m.outcome_labels.begin(), m.outcome_labels.end());
  for (std::size_t i = 0; i < m.asset_paths.size() && i < m.asset_texts.size(); ++i)
    s.assets.push_back({m.asset_paths[i], m.asset_texts[i]});
  return s;
}

}  // namespace dicesim::wire
