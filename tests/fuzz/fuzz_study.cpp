// The trade-off study spec parser (corpus: scenes/studies).
#include "study/tradeoff.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) {
    flume::study::parse_tradeoff_spec(t, "fuzz.json", FLUME_SOURCE_DIR "/scenes/studies");
  });
}
