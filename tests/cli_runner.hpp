// Runs the real `dicesim` binary from the repository root, as a user would, and captures its
// exit code, stdout and stderr. Shared by the command-line tests.
#pragma once

#include <gtest/gtest.h>

#include "temp_files.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

namespace dicesim::testing {

struct CliRun {
  int code = -1;
  std::string out, err;
};


// `args` go through the shell, so quoting works as on a command line.
inline CliRun run_dicesim(const std::string& args) {
  const std::string err_file = unique_temp("stderr.txt");
  const std::string cmd = std::string("cd ") + DICESIM_SOURCE_DIR + " && " + DICESIM_BINARY + " " + args + " 2>" + err_file;
  CliRun r;
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_file);
  std::stringstream ss;
  ss << e.rdbuf();
  r.err = ss.str();
  return r;
}

// Bad input: exit code 2, nothing on stdout, and stderr names each of `mentions`.
inline void expect_bad_input(const CliRun& r, std::initializer_list<const char*> mentions) {
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(r.out.empty()) << "stdout must stay empty on bad input: " << r.out;
  for (const char* m : mentions) EXPECT_NE(r.err.find(m), std::string::npos) << "stderr lacks '" << m << "': " << r.err;
}

}  // namespace dicesim::testing
