#include <robocal/planner/check.hpp>
#include <robocal/planner/health_plan.hpp>

#include <robocal/kinematics/units.hpp>

#include <cmath>
#include <cstdio>
#include <optional>

namespace robocal {
namespace {

constexpr double kPlaceToleranceMm = 1.0;  // ball vs the step's stated lat/lon

std::string ruleOf(const std::string& problem) {
  if (problem.rfind("joint ", 0) == 0) return "limits";
  if (problem.rfind("wrist", 0) == 0 && problem.find("singular") != std::string::npos)
    return "wrist singularity";
  if (problem.rfind("elbow", 0) == 0) return "elbow singularity";
  if (problem.find("shoulder singularity") != std::string::npos) return "shoulder singularity";
  if (problem.rfind("bar ", 0) == 0 && problem.find("tool axis") != std::string::npos)
    return "bar-tool angle";
  if (problem.rfind("flange", 0) == 0 && problem.find("from the bar") != std::string::npos)
    return "bar clearance";
  if (problem.rfind("flange", 0) == 0) return "table clearance";
  if (problem.rfind("bar deviation", 0) == 0) return "deviation";
  return "joints";
}

}  // namespace

std::string describeViolation(const PlanViolation& v) {
  std::string where = v.shell == 0 ? std::string("plan") : "shell " + std::to_string(v.shell);
  if (v.shell != 0 && v.step == kConnectStep) where += " connect pose";
  if (v.shell != 0 && v.step >= 0) where += " step " + std::to_string(v.step);
  return where + " (" + v.rule + "): " + v.message;
}

namespace {

// Moving through vias, every stretch between two stops along the path the controller blends:
// the first problem, at the step nearest it.
template <typename Add>
void checkBlendedPaths(const ShellPlanner& planner, const ShellPlan& shell, double tol,
                       const Add& add) {
  const MotionSettings& motion = planner.cell().motion;
  JointsDeg from = shell.connect.joints_deg;
  for (std::size_t first = 0; first < shell.steps.size();) {
    const Stretch stretch = stretchFrom(motion, shell.steps, first);
    const std::size_t last = stretch.last;
    const ShellPlanner::BlendProblem p = planner.blendedPathProblem(
        shell.connection, shell.radius_mm, from, stretch.joints_deg, tol);
    if (!p.problem.empty())
      add(static_cast<int>(first + p.nearest_step), ruleOf(p.problem),
          "on the path blended through the vias from step " + std::to_string(first) + " to " +
              std::to_string(last) + " (motion.blend_deg " + std::to_string(motion.blend_deg) +
              "): " + p.problem);
    from = shell.steps[last].joints_deg;
    first = last + 1;
  }
}

}  // namespace

std::vector<PlanViolation> checkPlan(const Model& model, const CellConfig& cell, const Plan& plan) {
  const ShellPlanner planner(model, cell);
  // The plan moves through vias as its own settings say (robocald runs it so).
  std::optional<ShellPlanner> blending;
  if (plan.cell.motion.through_vias) {
    CellConfig moving = cell;
    moving.motion.through_vias = true;
    moving.motion.blend_deg = plan.cell.motion.blend_deg;
    blending.emplace(model, moving);
  }
  const Arm& ik = planner.arm();
  const double tol = cell.motion.via_tolerance_mm;
  std::vector<PlanViolation> out;
  if (plan.shells.empty()) out.push_back({0, kShellStep, "empty", "the plan has no shells"});

  for (const ShellPlan& shell : plan.shells) {
    auto add = [&](int step, std::string rule, std::string message) {
      out.push_back({shell.shell, step, std::move(rule), std::move(message)});
    };
    const Connection c = shell.connection;
    if (c.ball_index < 0 || c.ball_index >= kBallCount || c.chuck_index < 0 ||
        c.chuck_index >= kChuckCount) {
      add(kShellStep, "connection", "no such ball or chuck");
      continue;
    }
    bool known_extension = false;
    for (double e : cell.bar.extension_lengths_mm)
      known_extension |= std::abs(e - shell.extension_mm) < 1e-6;
    // A check plan is checked against the calibration cell (robocald holds that one) or its own
    // settings: its extension is the calibration's check extension (health_plan.hpp).
    if (plan.purpose == PlanPurpose::kCheck)
      known_extension |= std::abs(healthCheckExtension(cell.bar) - shell.extension_mm) < 1e-6;
    char text[200];
    if (!known_extension) {
      std::snprintf(text, sizeof text,
                    plan.purpose == PlanPurpose::kCheck
                        ? "extension %.3f mm is neither one of the cell's nor its check extension"
                        : "extension %.3f mm is not one of the cell's",
                    shell.extension_mm);
      add(kShellStep, "extension", text);
    }
    const double radius = cell.bar.nominal_length_mm + shell.extension_mm;
    if (std::abs(shell.radius_mm - radius) > 1e-6) {
      std::snprintf(text, sizeof text,
                    "radius %.3f mm is not the bar's nominal length + extension = %.3f mm",
                    shell.radius_mm, radius);
      add(kShellStep, "radius", text);
    }
    int points = 0;
    for (const PlanStep& s : shell.steps) points += s.kind == StepKind::kPoint;
    if (points == 0) add(kShellStep, "empty", "the shell has no data points");

    auto checkPose = [&](int index, const PlanStep& step) {
      const std::string problem = planner.poseProblem(c, radius, step.joints_deg, tol);
      if (!problem.empty()) {
        add(index, ruleOf(problem), problem);
        return false;
      }
      if (!(ik.configOf(step.joints_deg) == shell.config)) {
        add(index, "configuration",
            "arm is " + armConfigName(ik.configOf(step.joints_deg)) + ", the shell's is " +
                armConfigName(shell.config));
        return false;
      }
      const Eigen::Vector3d n(
          std::cos(step.lat_deg * kRadPerDeg) * std::cos(step.lon_deg * kRadPerDeg),
          std::cos(step.lat_deg * kRadPerDeg) * std::sin(step.lon_deg * kRadPerDeg),
          std::sin(step.lat_deg * kRadPerDeg));
      const Eigen::Vector3d stated = model.chucks_mm[c.chuck_index] + radius * n;
      const double off = (planner.inspect(c, radius, step.joints_deg).ball_mm - stated).norm();
      if (off > kPlaceToleranceMm) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "ball is %.2f mm from its stated lat %.2f lon %.2f deg", off,
                      step.lat_deg, step.lon_deg);
        add(index, "place", buf);
        return false;
      }
      return true;
    };

    bool prev_ok = checkPose(kConnectStep, shell.connect);
    const PlanStep* prev = &shell.connect;
    for (size_t i = 0; i < shell.steps.size(); ++i) {
      const PlanStep& step = shell.steps[i];
      const bool ok = checkPose(static_cast<int>(i), step);
      if (prev_ok && ok) {
        // Along the move: the first sample that breaks a rule.
        const std::vector<JointsDeg> samples =
            planner.segmentSamples(c, prev->joints_deg, step.joints_deg);
        for (size_t k = 1; k + 1 < samples.size(); ++k) {
          const std::string problem = planner.poseProblem(c, radius, samples[k], tol);
          if (problem.empty()) continue;
          char buf[120];
          std::snprintf(buf, sizeof buf, "on the move from %s, %.0f%% of the way: ",
                        i == 0 ? "the connect pose" : ("step " + std::to_string(i - 1)).c_str(),
                        100.0 * k / (samples.size() - 1));
          add(static_cast<int>(i), ruleOf(problem), buf + problem);
          break;
        }
      }
      prev_ok = ok;
      prev = &step;
    }
    if (blending) checkBlendedPaths(*blending, shell, tol, add);
  }
  return out;
}

}  // namespace robocal
