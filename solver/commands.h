// Entry points of the solver's subcommands (`flume run`, `flume bench`, `flume check`).
#pragma once

namespace flume {
int run_main(int argc, char** argv);
int bench_main(int argc, char** argv);
int check_main(int argc, char** argv);
}  // namespace flume
