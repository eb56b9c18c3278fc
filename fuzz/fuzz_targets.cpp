// The targets file of robocal compensate (docs/compensation.md): CSV with a header row naming the
// pose or the joint columns. parseTargets returns the targets or throws FormatError. Properties:
// every target has exactly one form, the file's, with finite values; a pose is a rigid transform.
#include "fuzz_common.hpp"

#include <robocal/compensation/targets.hpp>

using namespace robocal;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    TargetFile file;
    try {
      file = parseTargets(text, "fuzz.csv");
    } catch (const FormatError&) {
      return;
    }
    for (const Target& t : file.targets) {
      check(t.line >= 2, "a target on the header's line");
      check(t.pose.has_value() != t.nominal_joints.has_value(), "not exactly one form");
      check(t.nominal_joints.has_value() == file.joints_form, "a target of the other form");
      if (t.nominal_joints) check(t.nominal_joints->allFinite(), "joints not finite");
      if (t.pose) {
        check(t.pose->matrix().allFinite(), "pose not finite");
        const Eigen::Matrix3d r = t.pose->linear();
        check((r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9,
              "pose rotation not orthonormal");
      }
      if (!file.has_names) check(t.name.empty(), "a name without a name column");
    }
  });
}
