// The fidelity ladder: which physical model a toss uses. Only `paper` exists so far;
// the others come with the fidelity-ladder work and are rejected with a clear error until then.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace dicesim {

enum class Fidelity { Paper };

inline const char* to_string(Fidelity f) {
  switch (f) {
    case Fidelity::Paper: return "paper";
  }
  return "?";
}

inline std::optional<Fidelity> parse_fidelity(std::string_view s) {
  if (s == "paper") return Fidelity::Paper;
  return std::nullopt;
}

inline constexpr const char* kFidelityChoices = "one of: paper";

}  // namespace dicesim
