// --log-level and --log-file: global options, accepted before or after the subcommand name, and
// the logging set-up they lead to, done once parsing is complete and before the subcommand runs.
#include <spdlog/spdlog.h>

#include "apps/commands.hpp"
#include "logger/log.hpp"

namespace dicesim {

void add_log_options(CLI::App& app, int argc, char** argv) {
  auto opt = std::make_shared<logging::LogOptions>(logging::default_log_options());
  const CLI::Validator level_check(
      [](std::string& s) -> std::string {
        return logging::parse_level(s) ? std::string() : "'" + s + "' is not a level; allowed: " + logging::kLevelNames;
      },
      "");
  auto add = [&](CLI::App* a) {
    a->add_option("--log-level", opt->level,
                  "Log level: trace, debug, info, warn, error, critical, off\n"
                  "(default: $DICESIM_LOG_LEVEL, else info). Logs go to stderr, never stdout")
        ->type_name("LEVEL")
        ->check(level_check)
        ->group("Logging");
    a->add_option("--log-file", opt->file,
                  "Also append every log line to PATH as one JSON object per line:\n"
                  "ts, level, component, run, worker, msg (default: $DICESIM_LOG_FILE)")
        ->type_name("PATH")
        ->group("Logging");
  };
  add(&app);
  for (CLI::App* sub : app.get_subcommands([](CLI::App* s) { return !s->get_name().empty(); })) add(sub);

  // The main app's parse-complete callback runs before the chosen subcommand's callback.
  app.parse_complete_callback([opt, &app, argc, argv] {
    const std::vector<CLI::App*> chosen = app.get_subcommands();
    opt->component = chosen.empty() ? app.get_name() : chosen.front()->get_name();
    try {
      logging::init(*opt);
    } catch (const std::exception& e) {  // a bad DICESIM_LOG_LEVEL or an unwritable file: bad input
      throw CLI::ValidationError(e.what());
    }
    logging::export_to_children();  // worker processes started by this one log the same way
    std::string line;
    for (int i = 0; i < argc; ++i) line += (i ? " " : "") + std::string(argv[i]);
    spdlog::debug("command line: {} (log level {})", line, logging::level_name(logging::current_level()));
  });
}

}  // namespace dicesim
