#include "apps/fit_parts.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "apps/provenance.hpp"
#include "sim/scene/scene_hash.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPrefix = "fit-part-";

}  // namespace

nlohmann::json fit_identity(const std::vector<FitParam>& params, const std::vector<FitData>& data, const FitOptions& opt) {
  nlohmann::json keys = nlohmann::json::array(), sets = nlohmann::json::array();
  for (const FitParam& p : params) keys.push_back({{"key", p.key}, {"lo", p.lo}, {"hi", p.hi}});
  for (const FitData& d : data) {
    std::vector<std::string> overrides = opt.overrides;
    overrides.insert(overrides.end(), d.overrides.begin(), d.overrides.end());
    nlohmann::json sha = nullptr;
    try {
      sha = scene_sha256(d.scene, overrides);
    } catch (const std::exception&) {  // not a file: the scene's name alone
    }
    sets.push_back({{"scene", d.scene}, {"scene_sha256", sha}, {"overrides", overrides}, {"labels", d.observed.labels},
                    {"counts", d.observed.counts}});
  }
  return {{"version", build_version()}, {"build", git_describe()}, {"params", keys}, {"data", sets}, {"seed", opt.seed},
          {"tosses", opt.tosses}, {"rounds", opt.rounds}, {"batches", opt.batches}};
}

std::string fit_part_path(const std::string& dir, int stage, Shard s) {
  return (fs::path(dir) / (kPrefix + std::string("s") + std::to_string(stage) + "-" + std::to_string(s.index) + "of" +
                           std::to_string(s.count) + ".json"))
      .string();
}

std::string write_fit_part(const std::string& dir, const nlohmann::json& identity, Shard s, const FitStageIncomplete& inc) {
  nlohmann::json points = nlohmann::json::array();
  for (const FitPointCounts& p : inc.tossed)
    points.push_back({{"point", p.point}, {"theta", p.theta}, {"tosses", p.tosses}, {"faces", p.faces}, {"settled", p.settled}});
  const nlohmann::json j = {{"fit_part",
                             {{"fit", identity},
                              {"index", s.index},
                              {"count", s.count},
                              {"stage", inc.stage},
                              {"label", inc.label},
                              {"stage_points", inc.stage_points},
                              {"points", points}}}};
  const std::string path = fit_part_path(dir, inc.stage, s), tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << j.dump() << "\n";
    if (!out) throw ShardError(tmp + ": cannot write the part file");
  }
  fs::rename(tmp, path);  // a reader sees the whole part or none
  return path;
}

FitParts read_fit_parts(const std::string& dir, const nlohmann::json& identity, std::uint64_t count) {
  FitParts parts;
  parts.count = count;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ShardError(dir + ": not a directory of fit parts");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(kPrefix, 0) == 0 && e.path().extension() == ".json") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());  // the same order on every machine
  for (const std::string& file : files) {
    std::ifstream in(file);
    if (!in) throw ShardError(file + ": cannot read it");
    try {
      const nlohmann::json j = nlohmann::json::parse(in);
      if (!j.is_object() || !j.contains("fit_part"))
        throw ShardError(file + ": not a fit part (no \"fit_part\" key; written by dicesim fit --points I/N --parts DIR)");
      const auto& p = j.at("fit_part");
      const auto& id = p.at("fit");
      if (id != identity) {
        std::string field = "?";
        for (const auto& [k, v] : identity.items())
          if (!id.contains(k) || id.at(k) != v) {
            field = k;
            break;
          }
        throw ShardError(file + ": a part of another fit (its " + field + " differs from this fit's; every part in " + dir +
                         " must come from one fit: the same build, scenes, data, keys, seed, tosses and rounds)");
      }
      const std::uint64_t n = p.at("count").get<std::uint64_t>();
      if (parts.count == 0) parts.count = n;
      if (n != parts.count)
        throw ShardError(file + ": shard count N " + std::to_string(n) + " differs from " + std::to_string(parts.count) +
                         " (every pass of a fit shards it the same way)");
      const int stage = p.at("stage").get<int>();
      for (const auto& q : p.at("points")) {
        FitPointCounts c;
        c.stage = stage;
        c.point = q.at("point").get<std::size_t>();
        c.theta = q.at("theta").get<std::vector<double>>();
        c.tosses = q.at("tosses").get<std::uint64_t>();
        c.faces = q.at("faces").get<std::vector<std::vector<std::uint64_t>>>();
        c.settled = q.at("settled").get<std::vector<std::uint64_t>>();
        c.origin = file;
        parts.points.push_back(std::move(c));
      }
      ++parts.files;
    } catch (const nlohmann::json::exception& e) {
      throw ShardError(file + ": not a readable fit part (" + e.what() + ")");
    }
  }
  return parts;
}

std::string missing_parts_message(const std::string& dir, std::uint64_t count, const FitStageIncomplete& inc) {
  if (count == 0) return dir + ": holds no fit parts (fit-part-*.json; write them with dicesim fit --points I/N --parts " + dir + ")";
  for (std::uint64_t i = 0; i < count; ++i) {
    const IndexRange b = shard_range(inc.stage_points, {i, count});
    std::vector<std::size_t> lacking;
    for (const std::size_t f : inc.missing)
      if (f >= b.first && f < b.first + b.tosses) lacking.push_back(f);
    if (lacking.empty()) continue;
    return fit_part_path(dir, inc.stage, {i, count}) + " is missing: stage " + std::to_string(inc.stage) + " (" + inc.label +
           ") has " + std::to_string(inc.missing.size()) + " of its " + std::to_string(inc.stage_points) +
           " points not counted, shard " + std::to_string(i) + "/" + std::to_string(count) +
           "'s among them (run every shard's pass again: dicesim fit ... --points I/N --parts " + dir + ")";
  }
  return dir + ": stage " + std::to_string(inc.stage) + " is not counted";
}

}  // namespace dicesim
