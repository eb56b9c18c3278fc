#include <robocal/planner/swaps.hpp>

#include <cstdio>

namespace robocal {

OperatorSteps operatorSteps(const Model& model, const Plan& plan) {
  OperatorSteps out;
  out.connects = static_cast<int>(plan.shells.size());
  for (size_t s = 1; s < plan.shells.size(); ++s) {
    const ShellPlan& before = plan.shells[s - 1];
    const ShellPlan& shell = plan.shells[s];
    if (shell.connection.chuck_index != before.connection.chuck_index) {
      ++out.chuck_changes;
      out.walk_mm += (model.chucks_mm[shell.connection.chuck_index] -
                      model.chucks_mm[before.connection.chuck_index])
                         .norm();
    }
    out.ball_changes += shell.connection.ball_index != before.connection.ball_index;
    out.extension_changes += shell.extension_mm != before.extension_mm;
  }
  return out;
}

std::string describeOperatorSteps(const OperatorSteps& steps) {
  auto plural = [](int n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  char walk[48];
  std::snprintf(walk, sizeof walk, " (%.1f m)", steps.walk_mm / 1000.0);
  return plural(steps.connects, "connect", "connects") + ": " +
         plural(steps.chuck_changes, "walk to another chuck", "walks to another chuck") + walk +
         ", " + plural(steps.ball_changes, "ball change", "ball changes") + ", " +
         plural(steps.extension_changes, "extension change", "extension changes");
}

}  // namespace robocal
