// Pictures by gnuplot (Debian's gnuplot-nox): a script written to a temporary file and run.
#pragma once

#include <string>

namespace dicesim {

// Writes `text` to `path`; throws std::runtime_error naming the path.
void write_text(const std::string& path, const std::string& text);
// A gnuplot string literal (double-quoted, newlines as \n).
std::string gnuplot_quote(const std::string& s);
// "set terminal ... / set output PATH" for a .svg or a .png (any other extension: png).
std::string gnuplot_terminal(const std::string& path, int width = 840, int height = 520);
// Runs the script; throws std::runtime_error with gnuplot's message, or how to install it. With
// DICESIM_PLOT_SCRIPT=FILE in the environment the script is also written to FILE (tests read it).
void run_gnuplot(const std::string& script, const std::string& path);

}  // namespace dicesim
