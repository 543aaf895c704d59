#include "apps/output_path.hpp"

#include <unistd.h>

#include <filesystem>

#include "sim/scene/scene_error.hpp"

namespace dicesim {

void check_output_path(const std::string& command, const std::string& option, const std::string& path) {
  namespace fs = std::filesystem;
  if (path.empty() || path == "-") return;
  auto bad = [&](const std::string& why) { throw SceneError(command, option, path, why); };
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_directory(p, ec)) bad("is a folder: give a file name");
  if (fs::exists(p, ec)) {
    if (access(path.c_str(), W_OK) != 0) bad("exists and is not writable");
    return;
  }
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::is_directory(dir, ec)) bad("cannot be written: the folder '" + dir.string() + "' does not exist");
  if (access(dir.c_str(), W_OK | X_OK) != 0) bad("cannot be written: the folder '" + dir.string() + "' is not writable");
}

}  // namespace dicesim
