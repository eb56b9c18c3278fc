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

#include <robocal/robot/arm.hpp>

#include <array>
#include <optional>
#include <string>
#include <utility>

namespace robocal {

class PumaIk final : public Arm {
 public:
  // True when the model's joint axes are a PUMA's (the constructor's checks).
  static bool isPumaChain(const Model& model);
  // Throws std::invalid_argument when the model's L1..L5 are not a PUMA-like chain (link
  // rotations more than a few degrees from the PUMA's alphas).
  explicit PumaIk(const Model& model);

  const char* ikName() const override { return "PUMA closed form"; }
  // True when the closed form lands within 20 mm and 2 deg of this model at three probe poses,
  // near enough for the refinement (makeArm takes the numeric IK otherwise).
  bool closedFormServes() const;

  // Closed form of the DH arm only (exact for a model made by modelFromStandardDH). `near`, when
  // given, picks among 360-degree turns of each joint the reading closest to it (else the one
  // closest to the middle of the joint's range); readings are always chosen inside the limits
  // when one is.
  IkSolution closedForm(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                        const JointsDeg* near = nullptr) const;
  // Closed form, then numerical refinement with the full model; the result keeps `config`. For a
  // model that is not exactly its DH part, where the closed form has no answer (near the edge of
  // the reach), the seeded descent (Arm::solveFromSeeds).
  IkSolution solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                   const JointsDeg* near = nullptr) const override;
  // Numerical refinement only, from `seed` (cheap when the seed is close, e.g. a previous model's
  // solution); checks the configuration and the limits like solve(). The iteration never leaves
  // `config` once in it; from a seed on the wrong side of one of this model's singularities, or
  // one it does not converge from, it starts again from this model's closed form (iterated on
  // the part of the model that is not DH). Converges on every reachable target of a calibrated
  // model away from the singularities (tests/planner/test_ik_convergence.cpp: models up to three
  // times as far from the nominal as a calibration finds them); a target out of this
  // configuration's reach is kUnreachable.
  IkSolution refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                    const JointsDeg& seed) const override;

  // The same names and margins as Arm's geometric ones (armGeometry), from the DH quantities in
  // closed form: the descent asks for them at every step.
  ArmConfig configOf(const JointsDeg& readings_deg) const override;
  SingularityMargins singularityMargins(const JointsDeg& readings_deg) const override;

 private:
  double theta(int joint, double reading_deg) const;  // rad
  double reading(int joint, double theta_rad) const;  // deg, not wrapped
  // This model's closed form, iterated on the target it misses by: a seed in `config` close to
  // the full model's answer; nullopt when the closed form has none.
  std::optional<JointsDeg> closedFormSeed(const Eigen::Isometry3d& target, const ArmConfig& config,
                                          const JointsDeg& near) const;
  // The largest miss (mm, deg) of the closed form at three probe poses of the full model;
  // infinite when it has no answer at one.
  std::pair<double, double> closedFormMiss() const;

  Eigen::Isometry3d base_inv_, tool_inv_;
  double a2_, a3_, d3_, d4_;
  double forearm_len_, forearm_angle_;  // |(a3, d4)| and atan2(d4, a3)
  // closedFormMiss() of this model: how far the closed form lands from it (0: exactly its DH).
  double miss_mm_ = 0, miss_deg_ = 0;
};

}  // namespace robocal
