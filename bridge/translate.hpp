// LCM message -> DDS sample, field by field (messages/probabilities.lcm -> probabilities.idl).
#pragma once

#include "dicesim_dds/probabilities.h"
#include "dicesim_lcm/probabilities.hpp"

namespace dicesim::bridge {

// The sample borrows m's per-outcome arrays (no copy, nothing to free): write it while m lives.
dicesim_dds_probabilities_v3 to_dds(const dicesim_lcm::probabilities& m);

}  // namespace dicesim::bridge
