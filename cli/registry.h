// The `flume` commands, one entry each. A new command adds one line to commands() in registry.cpp.
#pragma once
#include <vector>

namespace CLI {
class App;
}

namespace flume::cli {

struct Command {
  const char* name;
  const char* summary;  // one line, shown by `flume --help`
  // Either `add`: puts the command's options and subcommands on `app` (see common/command.h) ...
  void (*add)(CLI::App& app);
  // ... or `main`: a command that parses its own arguments (argv[0] is the command's name); it must answer
  // --help with exit 0 and bad usage with exit 2.
  int (*main)(int argc, char** argv);
};

const std::vector<Command>& commands();

}  // namespace flume::cli
