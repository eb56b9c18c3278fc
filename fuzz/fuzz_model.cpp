// The model file (config/puma560.json, docs/model-format.md). parseModel returns a Model or
// throws FormatError. Property: the model written back (formatModel) parses to the same values,
// exactly (the JSON writer prints doubles so that they read back unchanged).
#include "fuzz_common.hpp"

#include <robocal/formats/model_json.hpp>

using namespace robocal;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    const auto both = robocal::fuzz::readWriteRead<FormatError>(
        text, [](const std::string& t) { return parseModel(t, "fuzz.json"); }, formatModel,
        "written model does not parse");
    if (!both) return;
    const auto& [model, again] = *both;
    check(again.name == model.name, "name changed on a round trip");
    for (int k = 0; k < kLinkCount; ++k) {
      const LinkParams &a = model.links[k], &b = again.links[k];
      check(a.name == b.name && a.x_mm == b.x_mm && a.y_mm == b.y_mm && a.z_mm == b.z_mm &&
                a.rz_deg == b.rz_deg && a.ry_deg == b.ry_deg && a.rx_deg == b.rx_deg,
            "link changed on a round trip", std::to_string(k));
    }
    for (int j = 0; j < kJointCount; ++j) {
      const JointParams &a = model.joints[j], &b = again.joints[j];
      check(a.name == b.name && a.offset_deg == b.offset_deg && a.gain == b.gain &&
                a.min_deg == b.min_deg && a.max_deg == b.max_deg,
            "joint changed on a round trip", std::to_string(j));
    }
    for (int i = 0; i < kBallCount; ++i)
      check(model.balls_mm[i] == again.balls_mm[i], "ball changed on a round trip");
    for (int i = 0; i < kChuckCount; ++i)
      check(model.chucks_mm[i] == again.chucks_mm[i], "chuck changed on a round trip");
  });
}
