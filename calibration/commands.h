// `flume calibrate` on the command line (common/command.h):
//   flume calibrate SPEC.json --db FILE --out DIR [--workers N]
//   flume calibrate target RESULT.h5 --out CSV [--gauge NAME ...] [--noise-m SIGMA] [--seed N] [--from T0] [--to T1]
//   flume calibrate history --db FILE [--name NAME]
#pragma once

namespace CLI {
class App;
}

namespace flume::calibration {
void add_calibrate_command(CLI::App& app);
}  // namespace flume::calibration
