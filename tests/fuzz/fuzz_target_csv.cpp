// The calibration target CSV reader (corpus: the shipped gauge records).
#include "calibration/records.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) {
    flume::calibration::parse_target_csv(t, "fuzz.csv", {}, {"WG1", "WG2", "WG3", "WG4"}, 0.0, 1.0, 1.0,
                                         "targets.0");
  });
}
