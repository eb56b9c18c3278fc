// Inverse kinematics of a PUMA 560-like model: the closed form of the standard-DH arm (all eight
// configurations), refined numerically (Levenberg-Marquardt on the full model, with the
// tolerances and step limit of robocal::IkOptions) so that it also serves a calibrated model
// whose links are not exactly the DH ones. No I/O.
//
// The closed form works on the wrist-centre problem of the chain between L0 and L6:
//   T06 = L0^-1 * T * L6^-1,  A_k = Rz(theta_k) * Tz(d_k) Tx(a_k) Rx(alpha_k)
// with a2 = L2.x, a3 = L3.x, d3 = L3.z, d4 = L4.z taken from the model and the PUMA's alphas
// (90, 0, -90, 90, -90, 0 deg).
#pragma once

#include <robocal/kinematics/ik.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <array>
#include <optional>
#include <string>

namespace robocal {

// One of the PUMA's eight arm configurations.
//   shoulder: right when the wrist centre is in front of joint 1's axis in the arm's plane
//             (u = a2 c2 + a3 c23 - d4 s23 > 0), left otherwise.
//   elbow:    up when the elbow lies above the shoulder-to-wrist-centre line (along joint 1's
//             axis), seen from the side the arm reaches to.
//   wrist:    flip when sin(theta5) < 0.
struct ArmConfig {
  bool left = false;
  bool elbow_down = false;
  bool wrist_flip = false;
  friend bool operator==(const ArmConfig&, const ArmConfig&) = default;
};
inline constexpr int kArmConfigCount = 8;
ArmConfig armConfigFromIndex(int index);  // 0..7: bit 2 left, bit 1 elbow down, bit 0 flip
int armConfigIndex(const ArmConfig& config);
// "right-up-noflip", "left-down-flip", ...
std::string armConfigName(const ArmConfig& config);
// Inverse of armConfigName; nullopt for an unknown name.
std::optional<ArmConfig> parseArmConfig(const std::string& name);

enum class IkStatus {
  kOk,
  // The wrist centre is out of the arm's reach (or inside the shoulder offset). refine(): the
  // nearest pose the configuration reaches has the elbow straight or the wrist centre on the
  // shoulder plane, and misses the target; joints_deg is that pose.
  kUnreachable,
  kSingular,  // exactly at a wrist, elbow or shoulder singularity: the configuration is undefined
  kOutsideLimits,  // solved, but no 360-degree turn of a joint brings it inside the joint limits
  // The numerical refinement found no solution in the requested configuration, though the
  // target is not shown out of reach (not expected away from the singularities).
  kNoConvergence,
};
const char* ikStatusName(IkStatus status);

struct IkSolution {
  IkStatus status = IkStatus::kUnreachable;
  ArmConfig config;
  JointsDeg joints_deg = JointsDeg::Zero();  // always finite; meaningful for kOk / kOutsideLimits
  double position_error_mm = 0;              // |FK(joints) - target| of the full model
  double angle_error_deg = 0;
  bool ok() const { return status == IkStatus::kOk; }
};

// How far a pose is from the PUMA's three singularities (same geometry as the closed form).
struct SingularityMargins {
  double wrist_deg = 0;  // |theta5| from the nearest multiple of 180 deg (0 = axes 4 and 6 aligned)
  double elbow_deg = 0;  // bend of the elbow away from the straight (or folded) arm
  double shoulder_mm = 0;  // |u|: distance of the wrist centre from joint 1's axis plane
};

class PumaIk {
 public:
  // Throws std::invalid_argument when the model's L1..L5 are not a PUMA-like chain (link
  // rotations more than a few degrees from the PUMA's alphas).
  explicit PumaIk(const Model& model);

  const Model& model() const { return model_; }
  const Kinematics& kinematics() const { return kin_; }

  // Closed form of the DH arm only (exact for a model made by modelFromStandardDH). `near`, when
  // given, picks among 360-degree turns of each joint the reading closest to it (else the one
  // closest to the middle of the joint's range); readings are always chosen inside the limits
  // when one is.
  IkSolution closedForm(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                        const JointsDeg* near = nullptr) const;
  // Closed form, then numerical refinement with the full model; the result keeps `config`.
  IkSolution solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                   const JointsDeg* near = nullptr) const;
  // Numerical refinement only, from `seed` (cheap when the seed is close, e.g. a previous model's
  // solution); checks the configuration and the limits like solve(). The iteration never leaves
  // `config` once in it; from a seed on the wrong side of one of this model's singularities, or
  // one it does not converge from, it starts again from this model's closed form (iterated on
  // the part of the model that is not DH). Converges on every reachable target of a calibrated
  // model away from the singularities (tests/planner/test_ik_convergence.cpp: models up to three
  // times as far from the nominal as a calibration finds them); a target out of this
  // configuration's reach is kUnreachable.
  IkSolution refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                    const JointsDeg& seed) const;
  // All eight configurations (solve() of each), in armConfigFromIndex order.
  std::array<IkSolution, kArmConfigCount> solveAll(const Eigen::Isometry3d& tool_pose) const;

  ArmConfig configOf(const JointsDeg& readings_deg) const;
  SingularityMargins singularityMargins(const JointsDeg& readings_deg) const;

 private:
  double theta(int joint, double reading_deg) const;  // rad
  double reading(int joint, double theta_rad) const;  // deg, not wrapped
  // Picks the 360-degree turn of each reading; false when some joint fits no turn.
  bool wrapIntoLimits(JointsDeg& readings, const JointsDeg* near) const;
  void measureError(IkSolution& s, const Eigen::Isometry3d& target) const;
  struct Descent;
  // Levenberg-Marquardt on the full model's pose error from `seed`, keeping `config` (when
  // given) once in it.
  Descent descend(const Eigen::Isometry3d& target, const ArmConfig* config,
                  const JointsDeg& seed) const;
  // This model's closed form, iterated on the target it misses by: a seed in `config` close to
  // the full model's answer; nullopt when the closed form has none.
  std::optional<JointsDeg> closedFormSeed(const Eigen::Isometry3d& target, const ArmConfig& config,
                                          const JointsDeg& near) const;

  Model model_;
  Kinematics kin_;
  Eigen::Isometry3d base_inv_, tool_inv_;
  double a2_, a3_, d3_, d4_;
  double forearm_len_, forearm_angle_;  // |(a3, d4)| and atan2(d4, a3)
  IkOptions refine_options_;
};

}  // namespace robocal
