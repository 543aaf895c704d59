// Counts and thread numbers as people type them: `-n 1e5`, `-n 100_000` (an exact whole number in
// any form), `--threads 0` (all cores, as Python's threads=0). Applied once to every subcommand's
// -n/--tosses and -j/--threads, so each command's own registration stays as it is.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace dicesim {

// "1e5", "1.5e3", "100_000", "100000" -> "100000"; a value that is not an exact whole number
// (1.5, 1e-3, 1e30, abc) -> the error text CLI11 prints. Exposed for tests.
std::string whole_number_text(std::string& value);
// The cores of this machine (at least 1): what --threads 0 and the default mean.
int all_cores();
// Adds the forms above to -n/--tosses and -j/--threads of `app` and all its subcommands.
void accept_number_forms(CLI::App& app);

}  // namespace dicesim
