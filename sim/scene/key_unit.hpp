// The unit of a numeric scene key, for axis labels: "m", "kg/m^3", "rad/s", ...; "" for a
// dimensionless key (restitution, friction) or one the schema does not know. Read from the same
// ranges the scene reader checks values against (scene.cpp), so labels and errors agree.
#pragma once

#include <string>
#include <string_view>

namespace dicesim {

// `key` as --set writes it: "throw.height.mean", "materials.steel.density",
// "die.regions[0].cuts[0].offset" (indices and material names are ignored).
std::string key_unit(std::string_view key);

}  // namespace dicesim
