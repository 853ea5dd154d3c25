#include "calibration/stored_spec.h"

#include <nlohmann/json.hpp>

#include "campaigns/spec.h"
#include "common/errors.h"

namespace flume::calibration {

CalibrationSpec parse_stored_calibration_spec(const std::string& stored_json, const std::string& label) {
  using json = nlohmann::json;
  json spec = json::parse(stored_json);
  // The identity leaves out what does not change the results (budgets, profile, run settings): the parser
  // needs a budget, and a target is stored as {file (resolved), content (hash), spec (as written)}.
  spec.erase("scene_content");
  spec["algorithm"]["max_evaluations"] = 1;
  json targets = json::array();
  for (const auto& t : spec.at("targets")) {
    const std::string file = t.at("file").get<std::string>();
    if (campaigns::text_hash(read_target_text(file, "targets")) != t.at("content").get<std::string>())
      throw InputError(
          label, "targets",
          file + " has changed since the calibration fitted it: its evaluations no longer describe it");
    json target = t.at("spec");
    target["file"] = file;
    targets.push_back(target);
  }
  spec["targets"] = targets;
  return parse_calibration_spec(spec.dump(), label, "");
}

}  // namespace flume::calibration
