// The distributed commands as a user meets them before any network: help and bad input
// (exit 2, nothing on stdout, no process started). Runs that open LCM are integration tests.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace {

struct CmdRun {
  int code = -1;
  std::string out;
};

CmdRun dicesim(const std::string& args) {
  const std::string cmd = std::string("cd ") + DICESIM_SOURCE_DIR + " && " + DICESIM_BINARY + " " + args + " 2>/dev/null";
  CmdRun r;
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace

TEST(LcmCli, HelpTeachesWithExamples) {
  for (const char* c : {"worker", "aggregate", "run"}) {
    const CmdRun r = dicesim(std::string(c) + " --help");
    EXPECT_EQ(r.code, 0) << c;
    EXPECT_NE(r.out.find("Examples:"), std::string::npos) << c;
    EXPECT_NE(r.out.find("--lcm"), std::string::npos) << c;
  }
  EXPECT_NE(dicesim("toss --help").out.find("--target-halfwidth"), std::string::npos);
}

TEST(LcmCli, BadSceneIsBadInputBeforeAnyNetworking) {
  for (const char* c : {"aggregate scenes/nope.toml", "run scenes/nope.toml --workers 2",
                        "aggregate scenes/paper/die1.toml --set materials.steel.density=-1",
                        "run scenes/paper/die1.toml --workers 1 --set sim.nonsense=3",
                        "aggregate scenes/paper/die1.toml --target-halfwidth 2"}) {
    const CmdRun r = dicesim(c);
    EXPECT_EQ(r.code, 2) << c;
    EXPECT_TRUE(r.out.empty()) << c << ": " << r.out;
  }
}
