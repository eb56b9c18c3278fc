#include "compensate_request.hpp"

#include <robocal/compensation/compensate.hpp>

#include <cmath>

namespace robocal::daemon {

nlohmann::json compensateRequest(const ModelStore& models, const Model& nominal,
                                 const proto::Request& request) {
  std::string problem;
  const auto active = models.active(&problem);
  if (!active) return proto::errorObject(problem, "compensate");
  CompensationOptions options;
  if (const auto& t = request.tool_mm_deg)
    options.tool = poseFromXyzZyx((*t)[0], (*t)[1], (*t)[2], (*t)[3], (*t)[4], (*t)[5]);
  try {
    const Compensator compensator(nominal, active->model, options);
    proto::Compensated out;
    out.model = active->version;
    for (const proto::CompensateTarget& target : request.targets) {
      CompensatedTarget r;
      if (const auto& p = target.pose_mm_deg)
        r = compensator.forPose(
            poseFromXyzZyx((*p)[0], (*p)[1], (*p)[2], (*p)[3], (*p)[4], (*p)[5]));
      else
        r = compensator.forNominalJoints(JointsDeg(target.joints_deg->data()));
      proto::CompensatedRow row{target.name,
                                compensationStatusName(r.status),
                                armConfigName(r.config),
                                r.reason,
                                std::nullopt,
                                std::nullopt,
                                std::nullopt};
      if (r.hasJoints()) {
        std::array<double, 6> joints{};
        for (int j = 0; j < kJointCount; ++j) joints[j] = r.joints_deg[j];
        row.joints_deg = joints;
        if (r.hasApproach()) {
          for (int j = 0; j < kJointCount; ++j) joints[j] = r.pre_point_deg[j];
          row.pre_point_joints_deg = joints;
        }
      }
      if (!std::isnan(r.predicted_position_error_mm))
        row.predicted_error_mm = r.predicted_position_error_mm;
      out.targets.push_back(std::move(row));
    }
    return proto::toJson(out);
  } catch (const std::exception& e) {  // a model no arm serves (makeArm)
    return proto::errorObject(std::string("cannot compensate with model version ") +
                                  std::to_string(active->version) + ": " + e.what(),
                              "compensate");
  }
}

}  // namespace robocal::daemon
