// The distributed commands as a user meets them before any network: help and bad input
// (exit 2, nothing on stdout, no process started). Runs that open LCM are integration tests.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace {

struct CmdRun {
  int code = -1;
  std::string out;
};

// dicesim ARGS from the source folder, stderr to `err` (a path): exit code and stdout.
CmdRun dicesim_to(const std::string& args, const std::string& err) {
  const std::string cmd = std::string("cd ") + DICESIM_SOURCE_DIR + " && " + DICESIM_BINARY + " " + args + " 2>" + err;
  CmdRun r;
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

CmdRun dicesim(const std::string& args) { return dicesim_to(args, "/dev/null"); }

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

TEST(LcmCli, RunHelpSaysItsDefaultUrlIsAPrivatePort) {
  // `run` does not use the shared default URL (it picks a port of its own): its help must say so.
  const CmdRun r = dicesim("run --help");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("a port of this run's own"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("else udpm://239.255.76.67:7667?ttl=0"), std::string::npos) << "the shared URL is not run's default";
  EXPECT_NE(dicesim("aggregate --help").out.find("else udpm://239.255.76.67:7667?ttl=0"), std::string::npos);
}

// Exit code, stdout and stderr (through a file named after the process).
struct FullRun {
  int code = -1;
  std::string out, err;
};
FullRun dicesim_full(const std::string& args) {
  const std::string errf = ::testing::TempDir() + "dicesim_lcmcli_err_" + std::to_string(::getpid());
  const CmdRun r = dicesim_to(args, errf);
  std::ifstream in(errf);
  std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(errf.c_str());
  return {r.code, r.out, err};
}

TEST(LcmCli, BadKeyFilesAndCheckpointsAreBadInput) {
  const std::string dir = ::testing::TempDir() + "dicesim_keys_" + std::to_string(::getpid());
  ASSERT_EQ(std::system(("mkdir -p " + dir).c_str()), 0);
  const std::string open_key = dir + "/open.key", short_key = dir + "/short.key";
  std::ofstream(open_key) << std::string(64, 'a') << "\n";
  std::ofstream(short_key) << std::string(40, 'a') << "\n";
  ASSERT_EQ(std::system(("chmod 644 " + open_key + " && chmod 600 " + short_key).c_str()), 0);
  const std::string cases[] = {
      "aggregate scenes/paper/die1.toml --key-file " + open_key,  // group/other readable
      "run scenes/paper/die1.toml --workers 1 --key-file " + short_key,  // 20 bytes
      "worker --key-file " + dir + "/missing.key",
      "replay nothing.lcmlog --key-file " + short_key,
      "record -o " + dir + "/x.lcmlog --key-file " + open_key,
      "bridge --key-file " + short_key,
      "aggregate --resume " + dir + "/missing.ckpt",
      "aggregate --resume " + short_key,             // not a checkpoint
      "aggregate",                                    // neither SCENE nor --resume
      "aggregate scenes/paper/die1.toml --resume " + short_key,  // both
      "aggregate scenes/paper/die1.toml --checkpoint " + dir + "/no/such/dir/run.ckpt",
      "aggregate scenes/paper/die1.toml --checkpoint " + dir,   // a directory
  };
  for (const std::string& c : cases) {
    const FullRun r = dicesim_full(c);
    EXPECT_EQ(r.code, 2) << c << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << c << ": " << r.out;
  }
  const FullRun r = dicesim_full("aggregate scenes/paper/die1.toml --key-file " + open_key);
  EXPECT_NE(r.err.find("0644"), std::string::npos) << "names the mode: " << r.err;
  EXPECT_NE(r.err.find(open_key), std::string::npos) << "names the file: " << r.err;
  std::system(("rm -rf " + dir).c_str());
}
