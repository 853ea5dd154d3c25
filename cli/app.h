// The `flume` command line: the CLI11 tree of every registered command, and running it.
#pragma once
#include <memory>

namespace CLI {
class App;
}

namespace flume::cli {

// The whole command tree (every command of the registry with its subcommands and options).
std::unique_ptr<CLI::App> build_app();

// Parses argv, runs the chosen command and returns its exit code (common/errors.h): --help and --version 0,
// bad usage 2 with one line on stderr naming the option and pointing at --help.
int run(int argc, char** argv);

}  // namespace flume::cli
