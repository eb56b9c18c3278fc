// An arm as robocal moves it: its model and kinematics, its configurations (named branches of the
// inverse kinematics), its singularities and their margins, and its inverse kinematics, behind
// one interface. The planner, compensation, the simulators and the daemon hold an Arm; only
// robot/ knows which arm it is (makeArm). No I/O.
//
// Two implementations: PumaIk (puma_ik.hpp: the PUMA 560's closed form, refined numerically on
// the full model) and NumericIk (numeric_ik.hpp: damped least squares from several seeds, any
// six-revolute arm). Both name configurations the same way (armGeometry below), so a plan or a
// target keeps its configuration when an arm changes implementation.
#pragma once

#include <robocal/kinematics/ik.hpp>
#include <robocal/kinematics/kinematics.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

// One of a six-revolute arm's eight configurations (the three binary branches of its inverse
// kinematics), defined by the arm's geometry at a joint vector (armGeometry):
//   shoulder: right when the wrist point lies on the side of the plane of joints 1 and 2's axes
//             that the arm reaches to at zero (for the PUMA: in front of joint 1's axis in the
//             arm's plane), left otherwise;
//   elbow:    up when the elbow lies above the shoulder-to-wrist line, seen from the side the
//             arm reaches to;
//   wrist:    flip when joint 5 turns the wrist's last axis to the negative side (for the PUMA,
//             sin(theta5) < 0).
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
// The eight names, comma-separated in armConfigFromIndex order (for messages).
std::string armConfigNames();

enum class IkStatus {
  kOk,
  // The target is out of the arm's reach (or, for the PUMA's closed form, inside the shoulder
  // offset). refine(): joints_deg is the nearest pose the configuration reaches.
  kUnreachable,
  kSingular,  // exactly at a wrist, elbow or shoulder singularity: the configuration is undefined
  kOutsideLimits,  // solved, but no 360-degree turn of a joint brings it inside the joint limits
  // No solution found in the requested configuration, though the target is not shown out of
  // reach (not expected away from the singularities).
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

// How far a pose is from the arm's three singularities.
struct SingularityMargins {
  double wrist_deg = 0;    // angle between the axes of joints 4 and 6 (0: aligned)
  double elbow_deg = 0;    // bend of the elbow away from the straight (or folded) arm
  double shoulder_mm = 0;  // distance of the wrist point from the plane of joints 1 and 2's axes
};

// The geometry the configurations and margins are read from, for any six-revolute arm, from the
// joint axes at `readings` (Kinematics::chainFrames): the wrist point w (on joint 4's axis,
// nearest joint 5's; the wrist centre of a spherical wrist), the shoulder plane (through joint
// 1's axis, spanned by the axes of joints 1 and 2), the elbow's upper arm (joint 2's axis to
// joint 3's) and forearm (joint 3's axis to w) seen along joint 3's axis, and the wrist's axes
// 4, 5 and 6. shoulder_mm, elbow and wrist carry signs; configOf() reads the names from them.
struct ArmGeometry {
  double shoulder_mm = 0;  // signed distance of w from the shoulder plane
  double elbow = 0;        // signed sine of the elbow's bend
  double wrist = 0;        // axis 5 . (axis 4 x axis 6)
  SingularityMargins margins;
  ArmConfig config() const;
};
ArmGeometry armGeometry(const Kinematics& kin, const JointsDeg& readings_deg);

class Arm {
 public:
  virtual ~Arm() = default;
  Arm(const Arm&) = delete;
  Arm& operator=(const Arm&) = delete;

  const Model& model() const { return model_; }
  const Kinematics& kinematics() const { return kin_; }
  // Which inverse kinematics this arm uses ("PUMA closed form", "numeric"), for messages.
  virtual const char* ikName() const = 0;

  // The joint readings that put the tool (the last link's frame) at `tool_pose` in `config`.
  // `near`, when given, is tried first and picks among 360-degree turns of each joint the
  // reading closest to it (else the one closest to the middle of the joint's range); readings
  // are always chosen inside the limits when one is.
  virtual IkSolution solve(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                           const JointsDeg* near = nullptr) const = 0;
  // The same from `seed` (cheap when the seed is close, e.g. a previous model's solution); the
  // result keeps `config`. Converges on every reachable target away from the singularities.
  virtual IkSolution refine(const Eigen::Isometry3d& tool_pose, const ArmConfig& config,
                            const JointsDeg& seed) const = 0;
  // All eight configurations (solve() of each), in armConfigFromIndex order.
  std::array<IkSolution, kArmConfigCount> solveAll(const Eigen::Isometry3d& tool_pose) const;

  virtual ArmConfig configOf(const JointsDeg& readings_deg) const;
  virtual SingularityMargins singularityMargins(const JointsDeg& readings_deg) const;

 protected:
  explicit Arm(const Model& model);

  // One damped least-squares (Levenberg-Marquardt) descent of the pose error.
  struct Descent {
    JointsDeg q = JointsDeg::Zero();
    double cost = INFINITY;  // squared error, orientation weighed by orientation_scale_mm
    bool converged = false;  // within the options' tolerances
    int iterations = 0;      // Jacobians and refused steps
  };
  // From `seed`, never raising the error, and keeping `config` (when given) once in it.
  Descent descend(const Eigen::Isometry3d& target, const ArmConfig* config,
                  const JointsDeg& seed) const;
  bool found(const Descent& d, const ArmConfig& config) const {
    return d.converged && configOf(d.q) == config;
  }
  // Picks the 360-degree turn of each reading (nearest `near`, else the middle of the range);
  // false when some joint fits no turn.
  bool wrapIntoLimits(JointsDeg& readings, const JointsDeg* near) const;
  void measureError(IkSolution& s, const Eigen::Isometry3d& target) const;
  // The descent's squared pose error at `q` (orientation weighed by orientation_scale_mm).
  double poseCost(const Eigen::Isometry3d& target, const JointsDeg& q) const;
  // The status of a converged solution: singular, outside the limits (after wrapping its turns
  // towards `near`) or ok.
  void judgeConverged(IkSolution& s, const Eigen::Isometry3d& target, const JointsDeg* near) const;

  // The damped least-squares descent from several seeds: `near` first, then joint vectors drawn
  // once over the joint limits (a fixed table, built on first use, so answers repeat) in
  // `config`, nearest the target's tool pose first, at most kSeedsTried of them. A solution
  // counts when it reaches the target within the refinement's tolerances in `config`. When none
  // does: kNoConvergence if a descent free to take any configuration reaches the target from
  // the nearest seeds of each (it is in reach), else kUnreachable.
  IkSolution solveFromSeeds(const Eigen::Isometry3d& target, const ArmConfig& config,
                            const JointsDeg* near) const;
  static constexpr int kSeedCount = 4096;
  static constexpr int kSeedsTried = 24;

  Model model_;
  Kinematics kin_;
  IkOptions refine_options_;

 private:
  struct Seed {
    JointsDeg q;
    Eigen::Vector3d position_mm;
    Eigen::Quaterniond rotation;
  };
  // The table's seeds of `config`, nearest `target` first (position plus orientation weighed
  // by the refinement's orientation scale), at most `count`.
  std::vector<const Seed*> nearestSeeds(const Eigen::Isometry3d& target, const ArmConfig& config,
                                        int count) const;
  mutable std::once_flag seeds_built_;
  mutable std::array<std::vector<Seed>, kArmConfigCount> seeds_;  // by armConfigIndex
};

// The arm's whole range, beside a cell's declared work volume: `count` joint vectors drawn
// uniformly within the model's joint limits with `seed`, each at least `min_wrist_deg` from the
// wrist singularity (Arm::singularityMargins), where no compensation or fit says anything. What a
// calibration measured on a few shells says little about most of them: a prediction over these
// shows what it does not cover (docs/accuracy.md). A model whose wrist lives within the margin
// gets fewer vectors (at most 100 draws a vector), not a hang.
std::vector<JointsDeg> wholeRangeJoints(const Arm& arm, std::size_t count = 200,
                                        std::uint64_t seed = 1, double min_wrist_deg = 5);

// The arm for a model: the PUMA's closed form when the model is a PUMA-like chain, else the
// numeric inverse kinematics. Throws std::invalid_argument for a model neither serves (a zero
// joint gain).
std::shared_ptr<const Arm> makeArm(const Model& model);

}  // namespace robocal
