// The fidelity ladder: which physical model a toss uses (ARCHITECTURE.md, decision 4).
//   static  : no dynamics: random orientation, quasi-static roll to the resting face
//   paper   : the seed's model (frictionless vertex impulses, rebound-speed stop rule)
//   impulse : event-driven rigid body: exact flight, Coulomb friction in the impact law,
//             edge and face contacts solved together, sliding/rolling/tipping until rest
//   stepped : fixed-step time integration of the same physics (the reference as the step shrinks)
//   auto    : the cheapest model a pilot of paired tosses shows adequate for this scene at the
//             run's precision, else impulse (sim/study/auto_pilot.hpp); a scene file that names
//             no model runs auto
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace dicesim {

enum class Fidelity { Paper, Static, Impulse, Stepped, Auto };

inline const char* to_string(Fidelity f) {
  switch (f) {
    case Fidelity::Paper: return "paper";
    case Fidelity::Static: return "static";
    case Fidelity::Impulse: return "impulse";
    case Fidelity::Stepped: return "stepped";
    case Fidelity::Auto: return "auto";
  }
  return "?";
}

inline std::optional<Fidelity> parse_fidelity(std::string_view s) {
  if (s == "paper") return Fidelity::Paper;
  if (s == "static") return Fidelity::Static;
  if (s == "impulse") return Fidelity::Impulse;
  if (s == "stepped") return Fidelity::Stepped;
  if (s == "auto") return Fidelity::Auto;
  return std::nullopt;
}

inline constexpr const char* kFidelityChoices = "one of: static, paper, impulse, stepped, auto";

}  // namespace dicesim
