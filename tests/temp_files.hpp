// Files a test writes: one directory per test process, removed with its contents when the
// process exits.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace dicesim::testing {

// CTest runs tests as parallel processes: each process writes its files into its own directory
// (the pid in its name), removed with everything in it when the process exits, so thousands of
// runs do not fill the temp directory; every file also carries its test's name.
class ProcessTempDir {
 public:
  ProcessTempDir()
      : owner_(::getpid()), path_(std::filesystem::path(::testing::TempDir()) / ("dicesim_tests_" + std::to_string(owner_))) {}
  ~ProcessTempDir() {
    if (::getpid() != owner_) return;  // a forked child (a death test, a worker) that exits leaves it
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ProcessTempDir(const ProcessTempDir&) = delete;
  ProcessTempDir& operator=(const ProcessTempDir&) = delete;
  const std::filesystem::path& path() const {
    std::filesystem::create_directories(path_);
    return path_;
  }

 private:
  pid_t owner_;
  std::filesystem::path path_;
};
inline ProcessTempDir process_temp_dir;

inline std::string unique_temp(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return (process_temp_dir.path() / ("dicesim_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" + name)).string();
}

}  // namespace dicesim::testing
