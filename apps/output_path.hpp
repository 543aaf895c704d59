// Output files (--plot, --csv, --markdown, -o, --out ...) are checked before any work starts, so a
// long run never ends in "cannot write": a path whose folder is missing or not writable, that is a
// folder, or an existing file we may not write is bad input (exit 2, naming the option and path).
#pragma once

#include <string>

namespace dicesim {

// Throws SceneError(command, option, path, why) when `path` cannot be written; "" and "-" (stdout) pass.
void check_output_path(const std::string& command, const std::string& option, const std::string& path);

}  // namespace dicesim
