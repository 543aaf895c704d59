#include "bridge/dds_config.hpp"

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace dicesim::bridge {
namespace fs = std::filesystem;

namespace {

constexpr const char* kFileName = "cyclonedds-loopback.xml";

std::string file_uri(const fs::path& p) { return "file://" + fs::absolute(p).lexically_normal().string(); }

}  // namespace

std::vector<std::string> default_config_candidates(const std::string& exe_dir) {
  std::vector<std::string> out;
  if (!exe_dir.empty()) {
    out.push_back((fs::path(exe_dir) / ".." / "share" / "dicesim" / kFileName).lexically_normal().string());
    out.push_back((fs::path(exe_dir) / ".." / "bridge" / kFileName).lexically_normal().string());
  }
#ifdef DICESIM_SOURCE_DIR
  out.push_back((fs::path(DICESIM_SOURCE_DIR) / "bridge" / kFileName).lexically_normal().string());
#endif
  return out;
}

DdsConfigChoice resolve_dds_config(const std::string& flag, const char* env, const std::string& exe_dir) {
  std::error_code ec;
  if (!flag.empty()) {
    if (!fs::is_regular_file(flag, ec)) throw std::runtime_error("--dds-config: no such file: " + flag);
    return {file_uri(flag), "--dds-config"};
  }
  if (env != nullptr && *env != '\0') return {env, "CYCLONEDDS_URI"};
  for (const std::string& c : default_config_candidates(exe_dir))
    if (fs::is_regular_file(c, ec)) return {file_uri(c), "default"};
  throw std::runtime_error(std::string("no DDS configuration: ") + kFileName +
                           " not found next to the binary; give --dds-config FILE or set CYCLONEDDS_URI");
}

std::string executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

}  // namespace dicesim::bridge
