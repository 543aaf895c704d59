// LCM message -> DDS sample, field by field (messages/probabilities.lcm -> probabilities.idl).
#pragma once

#include "dicesim_dds/probabilities.h"
#include "dicesim_lcm/probabilities.hpp"

namespace dicesim::bridge {

dicesim_dds_probabilities to_dds(const dicesim_lcm::probabilities& m);

}  // namespace dicesim::bridge
