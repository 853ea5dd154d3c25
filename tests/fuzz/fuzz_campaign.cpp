// The campaign spec parser (corpus: scenes/campaigns); relative scene paths resolve from scenes/campaigns.
#include "campaigns/spec.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) {
    flume::campaigns::parse_campaign_spec(t, "fuzz.json", FLUME_SOURCE_DIR "/scenes/campaigns");
  });
}
