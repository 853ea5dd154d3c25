// The calibration spec parser (corpus: docs/calibration.md's example, pointed at shipped files).
#include "calibration/spec.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) {
    flume::calibration::parse_calibration_spec(t, "fuzz.json", FLUME_SOURCE_DIR "/scenes/studies");
  });
}
