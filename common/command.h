// What a module needs to put its command on the `flume` command line (CLI11): it adds its options and
// subcommands to the CLI::App it is given and says, with on_parse(), what runs once that command was parsed.
// cli/registry.cpp lists the commands; cli/app.cpp parses, runs the chosen action and maps errors to exit codes.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/errors.h"

namespace flume::cli {

using Action = std::function<int()>;

// The action of the command that was parsed last (the deepest subcommand on the line); empty before a parse.
inline Action& chosen_action() {
  static Action action;
  return action;
}

// `action` runs when `app` is the command given on the line. Options it reads must outlive the parse: keep them
// in a std::shared_ptr captured by the action. CLI11 calls a subcommand's callback before its parent's, so the
// first action set is the deepest command's.
inline void on_parse(CLI::App& app, Action action) {
  app.callback([action = std::move(action)] {
    if (!chosen_action()) chosen_action() = action;
  });
}

// Bad usage (an option's value out of range, a missing argument): reported as one line with a pointer to
// --help, exit code 2. Files with bad content throw InputError instead, which names the file and the field.
class UsageError : public std::runtime_error {
 public:
  UsageError(const std::string& option, const std::string& problem) : std::runtime_error(option + ": " + problem) {}
};

// `--set path=value`, repeatable, one value per flag (so that a positional argument after it stays positional).
inline CLI::Option* add_set_option(CLI::App& app, std::vector<std::string>& sets, const std::string& what) {
  return app.add_option("--set", sets, what)->allow_extra_args(false)->type_name("PATH=VALUE");
}

}  // namespace flume::cli
