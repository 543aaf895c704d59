// `dicesim show`: the page it writes, and its bad input (the browser tests are
// tests/integration/browser.sh).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "cli_runner.hpp"
#include "temp_files.hpp"

namespace {

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

TEST(CliShow, TossOutsideTheRunIsBadInput) {
  const std::string out = dicesim::testing::unique_temp("page.html");
  expect_bad_input(cli("show scenes/paper/die1.toml --toss 100000 -o " + out), {"--toss", "100000", "0..99999"});
  expect_bad_input(cli("show scenes/paper/die1.toml --toss 50 --tosses 50 -o " + out), {"--toss", "50", "0..49"});
  expect_bad_input(cli("show scenes/paper/die1.toml --toss -1 -o " + out), {"--toss", "-1"});
}

TEST(CliShow, UnwritableOutputIsBadInput) {
  expect_bad_input(cli("show scenes/paper/die1.toml -o /nonexistent-dir/page.html"), {"-o", "/nonexistent-dir/page.html"});
}

TEST(CliShow, WritesOnePageWithTheTossAndItsOutcome) {
  const std::string out = dicesim::testing::unique_temp("page.html");
  const CliRun r = cli("show scenes/paper/die1.toml --toss 77 --seed 3 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.out.empty());
  const std::string html = slurp(out);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_EQ(html.find("<script src"), std::string::npos);  // nothing loaded from elsewhere
  EXPECT_NE(html.find("\"toss\":{"), std::string::npos);
  EXPECT_NE(html.find("\"index\":77"), std::string::npos);
  // stderr names the outcome the page shows.
  EXPECT_NE(r.err.find("outcome "), std::string::npos) << r.err;
  const std::string stdout_page = cli("show scenes/paper/die1.toml --toss 77 --seed 3 -o -").out;
  EXPECT_EQ(stdout_page, html);
}

}  // namespace
