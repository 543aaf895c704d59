#include "apps/shard_file.hpp"
#include <algorithm>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "aggregator/counts_json.hpp"
#include "messages/run_spec.hpp"
#include "sim/scene/scene.hpp"

#ifndef DICESIM_VERSION
#define DICESIM_VERSION "unknown"
#endif

namespace dicesim {
namespace {

// The five count fields are aggregator/counts_json.hpp's (shared with checkpoints); the
// corrections here are an object by name, as the report prints them.
nlohmann::json counts_json(const RunCounts& c) { return agg::count_fields_json(c, corrections_json(c.corrections)); }

RunCounts counts_from(const nlohmann::json& j) {
  RunCounts c = agg::count_fields_from(j);
  // Every kind, by the names corrections_json writes (the first four alone dropped the sustained
  // phase's guards from a merged report).
  const auto& k = j.at("corrections");
  c.corrections.for_each([&](const char* name, std::uint64_t& n) { n = k.at(name).get<std::uint64_t>(); });
  return c;
}

std::string hex(std::uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

// What every shard of one run shares; `what` names it in the refusal.
void require_same(const ShardPart& first, const ShardPart& p, const std::string& a, const std::string& b, const char* what) {
  if (a != b)
    throw ShardError(p.file + ": " + what + " " + b + " differs from " + first.file + "'s " + a +
                     " (every shard of a merge must come from one run)");
}

}  // namespace

std::string build_version() { return DICESIM_VERSION; }

ShardHeader make_shard_header(const std::string& scene_path, const std::vector<std::string>& overrides,
                              const DieModel& model, std::uint64_t total, Shard s) {
  ShardHeader h;
  h.version = build_version();
  const SceneDef def = load_scene(scene_path, overrides);
  std::vector<std::string> asset_paths;
  if (!def.die.mesh_path.empty()) asset_paths.push_back(def.die.mesh_path);
  std::vector<wire::SceneFile> assets;
  std::vector<wire::SceneFile> files = wire::read_scene_files(scene_path, asset_paths, &assets);
  files.insert(files.end(), assets.begin(), assets.end());
  h.scene_hash = wire::scene_hash(files, overrides);
  h.fingerprint = hex(wire::model_fingerprint(model));
  h.total = total;
  h.shard = s;
  h.range = shard_range(total, s);
  return h;
}

nlohmann::json shard_json(const RunReport& r, const ShardHeader& h) {
  nlohmann::json j = report_json(r);
  j["shard"] = {{"version", h.version},
                {"scene_hash", h.scene_hash},
                {"model_fingerprint", h.fingerprint},
                {"index", h.shard.index},
                {"count", h.shard.count},
                {"first", h.range.first},
                {"tosses", h.range.tosses},
                {"total", h.total},
                {"labels", r.labels},
                {"faces_per_label", r.faces_per_label},
                {"names", r.names},
                {"counts", counts_json(r.counts)}};
  return j;
}

ShardPart read_shard_file(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw ShardError(file + ": cannot read it");
  ShardPart p;
  p.file = file;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.is_object() && j.contains("fit_part"))  // apps/fit_parts.hpp: merge needs the fit's arguments
      throw ShardError(file + ": a part of a fit sharded by point, not of a toss: print the fit with dicesim fit ARGS --merge " +
                       std::filesystem::path(file).parent_path().string() + " (the fit's own arguments)");
    if (!j.is_object() || !j.contains("shard"))
      throw ShardError(file + ": not a shard file (no \"shard\" key; write one with dicesim toss --shard I/N --out FILE)");
    const auto& s = j.at("shard");
    ShardHeader& h = p.header;
    h.version = s.at("version").get<std::string>();
    h.scene_hash = s.at("scene_hash").get<std::string>();
    h.fingerprint = s.at("model_fingerprint").get<std::string>();
    h.shard = {s.at("index").get<std::uint64_t>(), s.at("count").get<std::uint64_t>()};
    h.range = {s.at("first").get<std::uint64_t>(), s.at("tosses").get<std::uint64_t>()};
    h.total = s.at("total").get<std::uint64_t>();
    RunReport& r = p.report;
    r.scene = j.at("scene").get<std::string>();
    r.fidelity = j.at("fidelity").get<std::string>();
    r.seed = j.at("seed").get<std::uint64_t>();
    r.threads = j.at("threads").get<int>();
    r.tosses = j.at("tosses").get<std::uint64_t>();
    r.elapsed_s = j.at("elapsed_s").get<double>();
    r.labels = s.at("labels").get<std::vector<int>>();
    r.faces_per_label = s.at("faces_per_label").get<std::vector<int>>();
    r.names = s.at("names").get<std::vector<std::string>>();
    r.counts = counts_from(s.at("counts"));
    r.fidelity_requested = j.value("fidelity_requested", std::string());
    r.fidelity_reason = j.value("fidelity_reason", std::string());
    // The outcomes alike by design, as the toss's report found them from its model (merge has none):
    // groups of labels back to each outcome's first alike outcome (report.hpp, RunReport::alike).
    if (j.contains("alike") && j.at("alike").is_object()) {
      const auto& a = j.at("alike");
      r.alike.resize(r.labels.size());
      for (std::size_t i = 0; i < r.alike.size(); ++i) r.alike[i] = static_cast<int>(i);
      for (const auto& g : a.at("groups")) {
        int first = -1;
        for (const auto& label : g) {
          const auto at = std::find(r.labels.begin(), r.labels.end(), label.get<int>());
          if (at == r.labels.end()) throw ShardError(file + ": an alike group names label " + label.dump() + ", not an outcome");
          const int k = static_cast<int>(at - r.labels.begin());
          if (first < 0) first = k;
          r.alike[static_cast<std::size_t>(k)] = first;
        }
      }
      r.symmetry_rotations = a.at("rotations").get<int>();
      r.alike_note = a.at("note").get<std::string>();
    }
    // prov's provenance (apps/provenance.hpp), when the toss wrote one: the merged report carries it,
    // and its version (git describe) and resolved-scene SHA-256 must agree across shards too.
    if (j.contains("provenance")) {
      const auto& v = j.at("provenance");
      Provenance& pv = r.provenance;
      pv.version = v.at("version").get<std::string>();
      pv.dirty = v.at("dirty").is_null() ? -1 : (v.at("dirty").get<bool>() ? 1 : 0);
      pv.scene = v.at("scene").get<std::string>();
      pv.scene_sha256 = v.at("scene_sha256").get<std::string>();
      pv.overrides = v.at("overrides").get<std::vector<std::string>>();
      pv.fidelity = v.at("fidelity").get<std::string>();
      pv.fidelity_requested = v.at("fidelity_requested").get<std::string>();
      pv.fidelity_reason = v.at("fidelity_reason").get<std::string>();
      pv.seed = v.at("seed").get<std::uint64_t>();
      pv.tosses = v.at("tosses").get<std::uint64_t>();
      pv.threads = v.at("threads").get<int>();
    }
  } catch (const nlohmann::json::exception& e) {
    throw ShardError(file + ": not a readable shard file (" + e.what() + ")");
  }
  const ShardHeader& h = p.header;
  if (h.shard.count == 0 || h.shard.index >= h.shard.count)
    throw ShardError(file + ": shard " + std::to_string(h.shard.index) + "/" + std::to_string(h.shard.count) + " is not I/N with I < N");
  const IndexRange want = shard_range(h.total, h.shard);
  if (h.range.first != want.first || h.range.tosses != want.tosses || p.report.tosses != want.tosses ||
      p.report.counts.total() != want.tosses || p.report.counts.faces.size() != p.report.labels.size())
    throw ShardError(file + ": its block or counts do not match shard " + std::to_string(h.shard.index) + "/" +
                     std::to_string(h.shard.count) + " of " + std::to_string(h.total) + " tosses");
  return p;
}

RunReport merge_shards(const std::vector<ShardPart>& parts) {
  if (parts.empty()) throw ShardError("no shard files given");
  const ShardPart& first = parts.front();
  std::map<std::uint64_t, const ShardPart*> by_index;
  RunReport r = first.report;
  r.counts = RunCounts(static_cast<int>(first.report.labels.size()));
  r.threads = 0;
  r.elapsed_s = 0.0;
  for (const ShardPart& p : parts) {
    require_same(first, p, first.header.version, p.header.version, "dicesim version");
    require_same(first, p, first.header.scene_hash, p.header.scene_hash, "scene hash");
    require_same(first, p, first.report.provenance.version, p.report.provenance.version, "build (provenance version)");
    require_same(first, p, first.report.provenance.scene_sha256, p.report.provenance.scene_sha256, "scene sha256");
    require_same(first, p, first.header.fingerprint, p.header.fingerprint, "model fingerprint");
    require_same(first, p, first.report.fidelity, p.report.fidelity, "fidelity");
    require_same(first, p, std::to_string(first.report.seed), std::to_string(p.report.seed), "seed");
    require_same(first, p, std::to_string(first.header.total), std::to_string(p.header.total), "run size (tosses)");
    require_same(first, p, std::to_string(first.header.shard.count), std::to_string(p.header.shard.count), "shard count N");
    const auto [it, fresh] = by_index.emplace(p.header.shard.index, &p);
    if (!fresh)
      throw ShardError(p.file + ": shard " + std::to_string(p.header.shard.index) + " is also " + it->second->file +
                       " (overlapping shards: each index range may be counted once)");
    r.counts.merge(p.report.counts);
    r.threads += p.report.threads;
    r.elapsed_s += p.report.elapsed_s;
  }
  const std::uint64_t n = first.header.shard.count;
  for (std::uint64_t i = 0; i < n; ++i)
    if (!by_index.count(i))
      throw ShardError("shard " + std::to_string(i) + "/" + std::to_string(n) + " is missing (" +
                       std::to_string(parts.size()) + " of " + std::to_string(n) + " shards given, first " + first.file + ")");
  r.tosses = first.header.total;
  r.provenance.tosses = first.header.total;
  r.provenance.threads = r.threads;
  return r;
}

}  // namespace dicesim
