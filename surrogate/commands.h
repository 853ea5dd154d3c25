// Entry point of `flume surrogate ...`.
#pragma once

namespace flume {
// flume surrogate fit|predict|sobol|show --db FILE --campaign NAME --metric M ...
int surrogate_main(int argc, char** argv);
}  // namespace flume
