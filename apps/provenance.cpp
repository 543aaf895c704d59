#include "apps/provenance.hpp"

namespace dicesim {

Provenance make_provenance(const std::string& scene_path, const std::vector<std::string>& overrides,
                           const std::string& scene_sha256, const DieModel& model, std::uint64_t seed, std::uint64_t tosses,
                           int threads) {
  Provenance p;
  p.scene = scene_path;
  p.scene_sha256 = scene_sha256;
  p.overrides = overrides;
  p.fidelity = to_string(model.fidelity);
  p.fidelity_requested = to_string(model.fidelity_requested);
  p.fidelity_reason = model.fidelity_reason;
  p.seed = seed;
  p.tosses = tosses;
  p.threads = threads;
  return p;
}

nlohmann::json provenance_json(const Provenance& p) {
  return {{"version", p.version},
          {"dirty", p.dirty < 0 ? nlohmann::json(nullptr) : nlohmann::json(p.dirty == 1)},
          {"scene", p.scene},
          {"scene_sha256", p.scene_sha256},
          {"overrides", p.overrides},
          {"fidelity", p.fidelity},
          {"fidelity_requested", p.fidelity_requested},
          {"fidelity_reason", p.fidelity_reason},
          {"seed", p.seed},
          {"tosses", p.tosses},
          {"threads", p.threads}};
}

std::string provenance_lines(const Provenance& p) {
  std::string out = "dicesim " + p.version + (p.dirty < 0 ? " (not a git checkout)" : "") + ", scene sha256 " +
                    (p.scene_sha256.empty() ? "unknown" : p.scene_sha256) + "\noverrides: ";
  if (p.overrides.empty()) out += "none";
  for (std::size_t i = 0; i < p.overrides.size(); ++i) out += (i ? ", " : "") + p.overrides[i];
  out += "\nfidelity " + p.fidelity;
  if (p.fidelity_requested != p.fidelity && !p.fidelity_requested.empty()) out += " (asked: " + p.fidelity_requested + ")";
  out += ": " + (p.fidelity_reason.empty() ? std::string("no reason recorded") : p.fidelity_reason) + "\n";
  return out;
}

std::string provenance_csv_comment(const Provenance& p) { return "# provenance " + provenance_json(p).dump() + "\n"; }

}  // namespace dicesim
