// The scene parser on arbitrary text (corpus: the shipped scenes).
#include "solver/scene.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) { flume::parse_scene_text(t, "fuzz.json"); });
}
