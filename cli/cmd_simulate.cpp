// robocal simulate: a perturbed "true" robot and the ball-bar samples it would give.
#include "args.hpp"

#include <robocal/formats/model_json.hpp>
#include <robocal/formats/samples_csv.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/planner/plan_json.hpp>
#include <robocal/sim/measurements.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <algorithm>
#include <cmath>

#include <cstdio>

namespace robocal::cli {
namespace {

constexpr const char* kHelp = R"(usage: robocal simulate --model M [options]

Simulates ball-bar measurements of a "true" robot: the nominal model with all 54 parameters
perturbed (or a given truth), poses on each connection's shell found with the nominal model.

  --model FILE              nominal model (model format)                       required
  --truth FILE              use this true robot (a truth file, with its realism) instead of
                            perturbing the nominal
  --realism R               what the true robot carries beside its geometry: ideal (exactly its
                            model), typical (backlash, gravity compliance, warm-up, LVDT
                            errors: docs/realism.md), or a JSON file of realism keys  [ideal,
                            or the --truth file's]
  --minutes-per-point M     robot time a point costs (the warm-up's clock)        [0.1]
  --seed N                  random seed for the truth, the poses and the noise  [1]
  --noise-mm S              Gaussian length noise, standard deviation           [0.084]
  --quantum-deg Q           joint-reading quantisation (0 = exact)              [0]
  --connections LIST        all, or e.g. B1C1,B2C3                             [all]
  --bar-mm L                bar length at zero deflection without extension    [150]
  --extension-mm E          extension bar length                                [0]
  --points-per-shell N      grid points wanted per shell                        [90]
  --first-shell N           number of the first shell in the samples            [1]
  --sigma-translation-mm S  truth perturbation of link x, y, z                  [0.2]
  --sigma-link-angle-deg S  truth perturbation of link rz, ry, rx               [0.02]
  --sigma-offset-deg S      truth perturbation of joint offsets                 [0.05]
  --sigma-gain S            truth perturbation of joint gains                   [0.0005]
  --plan FILE               sample at this plan's data points (robocal plan) instead of the
                            simulator's own shells; excludes --connections, --bar-mm,
                            --extension-mm, --points-per-shell and --first-shell
  --out FILE                samples CSV to write                                [samples.csv]
  --truth-out FILE          write the true robot (model format, plus its realism)
)";

// What the realism did to these samples, in one line: the largest compliance twist, the warm-up.
std::string realismSummary(const TrueRobot& truth, const std::vector<Sample>& samples) {
  double twist_deg = 0;
  int joint = 0;
  for (const Sample& s : samples) {
    const auto torque =
        truth.gravityTorqueNm(s.joints_deg, truth.realism.compliance.load.payload_kg,
                              truth.realism.compliance.load.payload_com_mm);
    for (int j = 0; j < kJointCount; ++j) {
      const double t = std::abs(truth.realism.compliance.deg_per_nm[j] * torque[j]);
      if (t > twist_deg) twist_deg = t, joint = j + 1;
    }
  }
  char gravity[96] = "no gravity compliance (the model gives no link masses)";
  if (truth.realism.compliance.twists())
    std::snprintf(gravity, sizeof gravity,
                  "gravity compliance up to %.3g deg (joint %d) with a %.3g kg payload", twist_deg,
                  joint, truth.realism.compliance.load.payload_kg);
  char buf[320];
  std::snprintf(
      buf, sizeof buf,
      "realism: backlash up to %.3g deg; %s; warm-up %.3g K (tau %.3g min); LVDT gain error "
      "%.3g, nonlinearity %.3g mm; bar length error %.3g",
      *std::max_element(truth.realism.backlash_deg.begin(), truth.realism.backlash_deg.end()),
      gravity, truth.realism.warmup_k, truth.realism.warmup_time_constant_min,
      truth.realism.lvdt_gain_error, truth.realism.lvdt_nonlinearity_mm,
      truth.realism.bar_length_error);
  return buf;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"model", "truth", "seed", "noise-mm", "quantum-deg", "connections", "bar-mm",
                   "extension-mm", "points-per-shell", "first-shell", "sigma-translation-mm",
                   "sigma-link-angle-deg", "sigma-offset-deg", "sigma-gain", "out", "truth-out",
                   "plan", "realism", "minutes-per-point"},
                  {"help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model nominal = loadModelFile(args.required("model"));
  const long seed = args.integer("seed", 1);
  std::mt19937_64 truth_rng(seed), pose_rng(seed * 7919 + 1), noise_rng(seed * 104729 + 2);

  PerturbationSigmas sigmas;
  sigmas.translation_mm = args.number("sigma-translation-mm", sigmas.translation_mm);
  sigmas.link_angle_deg = args.number("sigma-link-angle-deg", sigmas.link_angle_deg);
  sigmas.joint_offset_deg = args.number("sigma-offset-deg", sigmas.joint_offset_deg);
  sigmas.gain = args.number("sigma-gain", sigmas.gain);
  TrueRobot true_robot =
      args.has("truth") ? loadTruthFile(args.get("truth", ""))
                        : TrueRobot{perturbModel(nominal, sigmas, truth_rng), Realism::ideal()};
  if (args.has("realism")) {
    // The arm's masses: the truth file's, else the nominal model's.
    const GravityLoad arm_load = args.has("truth")    ? true_robot.realism.compliance.load
                                 : nominal.compliance ? nominal.compliance->load
                                                      : GravityLoad{};
    true_robot.realism = realismNamed(args.get("realism", ""), arm_load);
  }
  const Model& truth = true_robot.model;
  RunTrack track;
  track.minutes_per_point = args.number("minutes-per-point", track.minutes_per_point);
  if (!(track.minutes_per_point >= 0)) throw UsageError("--minutes-per-point must not be negative");

  MeasurementNoise noise;
  noise.length_sigma_mm = args.number("noise-mm", noise.length_sigma_mm);
  noise.joint_quantum_deg = args.number("quantum-deg", 0);
  if (noise.length_sigma_mm < 0 || noise.joint_quantum_deg < 0)
    throw UsageError("--noise-mm and --quantum-deg must not be negative");
  const double bar_mm = args.number("bar-mm", kDefaultBarMm);
  const double extension_mm = args.number("extension-mm", 0);
  const long points = args.integer("points-per-shell", 90);
  if (bar_mm + extension_mm <= 0) throw UsageError("--bar-mm plus --extension-mm must be positive");
  if (points < 1 || points > 100000) throw UsageError("--points-per-shell must be 1 to 100000");

  std::vector<Sample> samples;
  int shell = static_cast<int>(args.integer("first-shell", 1));
  const Kinematics nominal_kin(nominal), true_kin(truth);
  double worst_offset_mm = 0;
  // The shells: the plan's, or the simulator's own grid on each connection.
  std::vector<std::pair<ShellRequest, ShellPoses>> shells;
  // How every point is reached, recorded with it: the plan's approach pre-points, else none
  // (the simulator's own grid goes straight from point to point).
  double approach_deg = 0;
  if (args.has("plan")) {
    for (const char* option :
         {"connections", "bar-mm", "extension-mm", "points-per-shell", "first-shell"})
      if (args.has(option)) throw UsageError(std::string("--plan excludes --") + option);
    const Plan plan = loadPlanFile(args.get("plan", ""));
    approach_deg = plan.cell.motion.approach_deg;
    for (const ShellPlan& s : plan.shells) {
      ShellRequest req;
      req.connection = s.connection;
      req.radius_mm = s.radius_mm;
      req.extension_mm = s.extension_mm;
      req.shell = s.shell;
      ShellPoses poses;
      std::vector<JointsDeg> vias;  // the arm's way to the next point
      for (const PlanStep& step : s.steps) {
        if (step.kind == StepKind::kPoint) {
          poses.poses.push_back({step.lat_deg, step.lon_deg, step.joints_deg, vias});
          vias.clear();
        } else {
          vias.push_back(step.joints_deg);
        }
      }
      poses.dropped = static_cast<int>(s.dropped.size());
      req.points = static_cast<int>(poses.poses.size());
      shells.emplace_back(req, std::move(poses));
    }
  } else {
    for (const Connection& c : parseConnections(args.get("connections", "all"))) {
      ShellRequest req;
      req.connection = c;
      req.radius_mm = bar_mm + extension_mm;
      req.extension_mm = extension_mm;
      req.points = static_cast<int>(points);
      req.shell = shell++;
      shells.emplace_back(req, shellPoses(nominal, req, pose_rng));
    }
  }
  for (const auto& [req, poses] : shells) {
    const Connection& c = req.connection;
    auto shell_samples = measureShell(true_robot, req, poses.poses, noise, noise_rng, track);
    for (Sample& s : shell_samples) s.approach_deg = approach_deg;
    for (const ShellPose& p : poses.poses) {
      const Eigen::Vector3d& ball = nominal.balls_mm[c.ball_index];
      worst_offset_mm = std::max(worst_offset_mm, (true_kin.ballPosition(p.joints_deg, ball) -
                                                   nominal_kin.ballPosition(p.joints_deg, ball))
                                                      .norm());
    }
    std::printf("shell %2d %s radius %.1f mm: %zu points, %d grid points unreachable\n", req.shell,
                connectionName(c).c_str(), req.radius_mm, poses.poses.size(), poses.dropped);
    samples.insert(samples.end(), shell_samples.begin(), shell_samples.end());
  }
  const std::string out = args.get("out", "samples.csv");
  saveSamplesFile(out, samples);
  std::printf(
      "wrote %zu samples to %s (noise %.3f mm); the truth puts the balls up to %.2f mm "
      "from the nominal\n",
      samples.size(), out.c_str(), noise.length_sigma_mm, worst_offset_mm);
  if (!true_robot.realism.isIdeal())
    std::printf("%s\n", realismSummary(true_robot, samples).c_str());
  if (args.has("truth-out")) {
    saveTruthFile(args.get("truth-out", ""), true_robot);
    std::printf("wrote the true model to %s\n", args.get("truth-out", "").c_str());
  }
  return 0;
}

const RegisterCommand registered({"simulate", "simulated ball-bar samples of a perturbed robot",
                                  run});

}  // namespace
}  // namespace robocal::cli
