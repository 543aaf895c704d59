#include "aggregator/counts_json.hpp"

#include <cstdint>
#include <utility>
#include <vector>

namespace dicesim::agg {

// Every field of RunCounts: a field added there (e.g. counted corrections, or N outcomes instead
// of 6) must be added here and in both callers' corrections, or a resumed run or a merge would
// lose it. The assertion makes such a change stop here until it is.
static_assert(sizeof(RunCounts) == sizeof(std::vector<std::uint64_t>) + 4 * sizeof(std::uint64_t) + sizeof(RunCorrections) &&
                  sizeof(RunCorrections) == RunCorrections::kKinds * sizeof(std::uint64_t),
              "RunCounts changed: serialise the new fields in count_fields_json / count_fields_from and the callers");

nlohmann::json count_fields_json(const RunCounts& c, nlohmann::json corrections) {
  return {{"faces", c.faces},     {"settled", c.settled}, {"unresolved", c.unresolved},
          {"invalid", c.invalid}, {"bounces", c.bounces}, {"corrections", std::move(corrections)}};
}

RunCounts count_fields_from(const nlohmann::json& j) {
  RunCounts c;
  c.faces = j.at("faces").get<std::vector<std::uint64_t>>();
  c.settled = j.at("settled").get<std::uint64_t>();
  c.unresolved = j.at("unresolved").get<std::uint64_t>();
  c.invalid = j.at("invalid").get<std::uint64_t>();
  c.bounces = j.at("bounces").get<std::uint64_t>();
  return c;
}

}  // namespace dicesim::agg
