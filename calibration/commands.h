// `flume calibrate`: argument parsing and reporting only.
//   flume calibrate SPEC.json --db FILE --out DIR [--workers N]
//   flume calibrate target RESULT.h5 --out CSV [--gauge NAME ...] [--noise-m SIGMA] [--seed N] [--from T0]
//   [--to T1] flume calibrate history --db FILE [--name NAME]      the evaluations in the store, as CSV on
//   stdout
#pragma once

namespace flume::calibration {
int calibrate_main(int argc, char** argv);
}  // namespace flume::calibration
