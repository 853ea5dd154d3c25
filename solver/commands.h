// The solver's commands (`flume run`, `flume bench`, `flume check`) on the command line (common/command.h).
#pragma once

namespace CLI {
class App;
}

namespace flume {
void add_run_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_check_command(CLI::App& app);
}  // namespace flume
