// How this binary was built, for `dicesim version --json`: the compiler, its flags and the library
// versions CMake found at configure time (apps/build_config.cpp.in, generated into the build tree).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace dicesim {

struct BuildConfig {
  std::string compiler;    // e.g. "GNU 12.2.0"
  std::string build_type;  // e.g. "Release"
  std::string cxx_flags;   // CMAKE_CXX_FLAGS, the build type's flags and the project's compile options
  std::vector<std::pair<std::string, std::string>> libraries;  // name, version ("" when CMake did not say)
};

BuildConfig build_config();

}  // namespace dicesim
