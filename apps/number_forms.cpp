#include "apps/number_forms.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>

namespace dicesim {

std::string whole_number_text(std::string& value) {
  std::string s;
  for (char c : value)
    if (c != '_') s += c;
  if (s.empty()) return "'" + value + "' is not a number";
  if (s.find_first_not_of("0123456789") == std::string::npos) {
    value = s;
    return {};
  }
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  // 2^53: every whole number below it is exact in a double, so 1e15 means exactly 10^15.
  if (end == s.c_str() || *end != '\0' || !std::isfinite(x) || x < 0 || x != std::floor(x) || x >= 9007199254740992.0)
    return "'" + value + "' is not a whole number (write e.g. 100000, 1e5 or 100_000)";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f", x);
  value = buf;
  return {};
}

int all_cores() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

namespace {

void add_forms(CLI::App& app) {
  if (CLI::Option* n = app.get_option_no_throw("--tosses"))
    n->transform(CLI::Validator([](std::string& v) { return whole_number_text(v); }, "", "whole number"));
  if (CLI::Option* j = app.get_option_no_throw("--threads")) {
    j->transform(CLI::Validator(
        [](std::string& v) {
          if (v == "0") v = std::to_string(all_cores());
          return std::string{};
        },
        "", "0 is all cores"));
    j->description(j->get_description() + " (0: all cores, " + std::to_string(all_cores()) + " here)");
  }
  for (CLI::App* sub : app.get_subcommands({})) add_forms(*sub);
}

}  // namespace

void accept_number_forms(CLI::App& app) { add_forms(app); }

}  // namespace dicesim
