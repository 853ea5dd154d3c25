// `--set` overrides on the Waseda 2D scene: each input line is one `path=value` (corpus: overrides the docs
// and tests use).
#include <sstream>
#include <vector>

#include "solver/scene.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string scene = flume::read_scene_file(FLUME_SOURCE_DIR "/scenes/waseda/waseda_2d.json");
  return flume::fuzz::accept_or_input_error(data, size, [](const std::string& t) {
    std::vector<flume::Override> sets;
    std::istringstream lines(t);
    for (std::string line; std::getline(lines, line);) sets.push_back(flume::parse_override(line));
    flume::parse_scene_text(scene, "waseda_2d.json", sets);
  });
}
