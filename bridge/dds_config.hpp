// Which Cyclone DDS configuration the bridge uses. DDS must never reach further than the user
// asked, so the bridge always has an explicit configuration:
//   1. --dds-config FILE (explicit wins),
//   2. else $CYCLONEDDS_URI (Cyclone's own variable, as every Cyclone program reads it),
//   3. else the repository's loopback-only file, bridge/cyclonedds-loopback.xml, found next to
//      the binary: <bin>/../share/dicesim/ (installed), <bin>/../bridge/ (a build tree, which
//      copies it there), then the source tree the binary was built from.
// With none of them found the bridge refuses to start rather than fall back to Cyclone's
// defaults (which pick a real interface).
#pragma once

#include <string>
#include <vector>

namespace dicesim::bridge {

struct DdsConfigChoice {
  std::string uri;     // for dds_create_domain / CYCLONEDDS_URI: "file:///abs/path.xml" or XML text
  std::string source;  // "--dds-config", "CYCLONEDDS_URI" or "default" (for the log)
};

// Where the default file may be, in order, for a binary in `exe_dir`.
std::vector<std::string> default_config_candidates(const std::string& exe_dir);

// `flag` is --dds-config ("" if absent), `env` is $CYCLONEDDS_URI (nullptr or "" if unset).
// Throws std::runtime_error if the flag's file does not exist or no default file is found.
DdsConfigChoice resolve_dds_config(const std::string& flag, const char* env, const std::string& exe_dir);

// The directory of the running executable ("" if unknown).
std::string executable_dir();

}  // namespace dicesim::bridge
