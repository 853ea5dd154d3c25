// `flume`: the thin command line over the solver, campaign, calibration and report modules. The commands are
// listed in cli/registry.cpp; each module puts its options on the line in its own commands.cpp.
#include "cli/app.h"

int main(int argc, char** argv) { return flume::cli::run(argc, argv); }
