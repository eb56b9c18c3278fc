// The plan file (docs/plan-format.md), which robocal and robocald load from disk or a client's
// path. parsePlan returns a Plan or throws FormatError. Property: the plan written back
// (formatPlan) parses to the same plan; the writer rounds to 1e-9, so numbers compare to that.
#include "fuzz_common.hpp"

#include <robocal/planner/plan_json.hpp>

using namespace robocal;
using robocal::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return robocal::fuzz::guarded(data, size, [](const std::string& text) {
    const auto both = robocal::fuzz::readWriteRead<FormatError>(
        text, [](const std::string& t) { return parsePlan(t, "fuzz.json"); }, formatPlan,
        "written plan does not parse");
    if (!both) return;
    const auto& [plan, again] = *both;
    std::string path = "plan";
    check(robocal::fuzz::sameJson(planToJson(plan), planToJson(again), 1e-9, 1e-12, path),
          "plan changed on a round trip", path);
  });
}
