#include "apps/gnuplot.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <sys/wait.h>
#include <unistd.h>

namespace dicesim {

namespace fs = std::filesystem;

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << text;
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
}

std::string gnuplot_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string gnuplot_terminal(const std::string& path, int width, int height) {
  const std::string size = std::to_string(width) + "," + std::to_string(height);
  std::string t = fs::path(path).extension() == ".svg"
                      ? "set terminal svg size " + size + " dynamic font 'sans,11' background rgb 'white'\n"
                      : "set terminal pngcairo size " + size + " font 'sans,10' background rgb 'white'\n";
  return t + "set output " + gnuplot_quote(path) + "\n";
}

void run_gnuplot(const std::string& script_text, const std::string& path) {
  const fs::path script = fs::temp_directory_path() / ("dicesim-plot-" + std::to_string(::getpid()) + ".gp");
  const fs::path err = fs::temp_directory_path() / ("dicesim-plot-" + std::to_string(::getpid()) + ".err");
  write_text(script.string(), script_text);
  // Tests read what was drawn (labels, ranges, lines) from the script, not from the picture.
  if (const char* keep = std::getenv("DICESIM_PLOT_SCRIPT"); keep && *keep) write_text(keep, script_text);
  const std::string cmd = "gnuplot " + script.string() + " 2>" + err.string();
  const int rc = std::system(cmd.c_str());
  std::string err_text;
  {
    std::ifstream e(err);
    std::stringstream ss;
    ss << e.rdbuf();
    err_text = ss.str();
  }
  fs::remove(script);
  fs::remove(err);
  if (rc != 0) {
    if (WIFEXITED(rc) && WEXITSTATUS(rc) == 127)
      throw std::runtime_error("--plot needs gnuplot: install the Debian package gnuplot-nox (scripts/setup does)");
    throw std::runtime_error("gnuplot failed writing '" + path + "': " + err_text);
  }
}

}  // namespace dicesim
