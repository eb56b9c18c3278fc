#include <robocal/calibration/plan_pipeline.hpp>

#include <robocal/compensation/accuracy.hpp>
#include <robocal/compensation/compensate.hpp>
#include <robocal/planner/health_plan.hpp>
#include <robocal/sim/measurements.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace robocal {
namespace {

// The robots the forecast runs the plan with: the model perturbed as the cell's
// model_uncertainty says a nominal model is off.
std::vector<Model> uncertainRobots(const Model& model, const ModelUncertainty& u) {
  PerturbationSigmas sigmas;
  sigmas.translation_mm = u.translation_sigma_mm;
  sigmas.link_angle_deg = u.link_angle_sigma_deg;
  sigmas.joint_offset_deg = u.joint_offset_sigma_deg;
  sigmas.gain = u.gain_sigma;
  std::mt19937_64 rng(static_cast<std::uint64_t>(u.seed));
  std::vector<Model> robots;
  robots.reserve(static_cast<std::size_t>(std::max(0, u.models)));
  for (int i = 0; i < u.models; ++i) robots.push_back(perturbModel(model, sigmas, rng));
  return robots;
}

}  // namespace

PlannedCell planCalibration(const Model& model, const CellConfig& calibration_cell,
                            const PlanRequest& request) {
  const bool check = request.kind == PlanKind::kCheck;
  PlannedCell out;
  DesignOptions design = request.design;
  const Compensator nominal_only(model, model);
  const std::vector<JointsDeg> whole_joints = wholeRangeJoints(nominal_only.nominalArm());
  design.whole_range_joints = whole_joints;
  out.cell = check ? healthCheckCell(calibration_cell) : calibration_cell;
  const std::vector<JointsDeg> work_joints = workVolumeJoints(out.cell.work_volume, nominal_only);
  out.work_poses = work_joints.size();
  out.whole_poses = whole_joints.size();
  switch (request.kind) {
    case PlanKind::kOptimal:
      out.plan = planOptimal(model, out.cell, work_joints, design, &out.design_report);
      break;
    case PlanKind::kCheck:
      out.plan = planHealthCheck(model, calibration_cell);
      break;
    case PlanKind::kGrid:
      out.plan = planCell(model, out.cell);
      summarizeIdentifiability(model, out.plan);  // planOptimal and the check do it themselves
      break;
  }

  // A calibration plan's accuracy where the user works and beyond (a check is not fitted).
  if (!check) {
    PlanSummary& s = out.plan.summary;
    const double work_mm = predictedWorkVolumeError(model, out.plan, work_joints,
                                                    design.noise_sigma_mm, design.compliance);
    const double whole_mm = predictedWorkVolumeError(model, out.plan, whole_joints,
                                                     design.noise_sigma_mm, design.compliance);
    if (std::isfinite(work_mm)) {
      s.predicted_work_volume_error_mm = work_mm;
      if (std::isfinite(whole_mm)) s.predicted_whole_range_error_mm = whole_mm;
      s.noise_sigma_mm = design.noise_sigma_mm;
    }
  }
  out.forecast = !(check && model.provenance);
  if (out.forecast)
    predictDeflections(model, uncertainRobots(model, out.cell.uncertainty), out.plan);
  return out;
}

}  // namespace robocal
