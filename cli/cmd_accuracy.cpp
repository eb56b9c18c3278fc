// robocal accuracy: how accurate the robot is where the user works, before and after
// compensation (compensation/accuracy.hpp, docs/compensation.md).
#include "args.hpp"
#include "model_args.hpp"

#include <robocal/compensation/accuracy_report.hpp>
#include <robocal/compensation/targets.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/planner/cell_json.hpp>
#include <robocal/sim/true_robot_json.hpp>

#include <cstdio>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal accuracy --calibrated CALIBRATED [--nominal NOMINAL] [--truth TRUE]
                        [--cell cell.json | --poses FILE | --whole-range N]
                        [--tool x,y,z,rz,ry,rx]
                        [--json] [--svg FILE]

Tool position and orientation error over the work volume: the calibrated model's predicted
1-sigma error (from its covariance; needs no truth) and, for a simulation's true robot, the
error of the true robot commanded with the nominal joints and with the compensated joints
(RMS, p95, max). The poses are the cell file's work_volume (docs/compensation.md; without
--cell and --poses, the reference cell's), a targets file (robocal compensate's forms), or the
arm's whole range (beyond where the user works: what the calibration does not cover).

  --calibrated FILE     the calibrated model                                      required
  --nominal FILE        the controller's model: only a check, refused when it differs from
                        the one recorded in CALIBRATED              [the recorded one, else
                        the built-in model of its name; else required]
  --truth FILE          a simulation's true robot (robocal simulate --truth-out); with its
                        realism, judged warm, with its payload, each target reached as the
                        output commands it: up from its pre-point when the model records
                        an approach, else from either side (as the nominal joints)
  --cell FILE           cell file: its work_volume section
  --poses FILE          targets CSV instead of the work volume
  --whole-range N       N joint vectors drawn within the arm's limits instead (their nominal
                        tool poses, in their configurations)
  --tool X,Y,Z,RZ,RY,RX tool centre point in the ball fixture's frame (mm, deg)  [0,...]
  --json                one JSON object (with every pose) instead of text
  --svg FILE            write a map of the error over the volume (seen from above)

exit status: 0 done, 1 an unreadable input, 2 a usage error
)";

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"nominal", "calibrated", "truth", "cell", "poses", "tool", "svg", "whole-range"},
                  {"json", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model calibrated = loadModelFile(args.required("calibrated"));
  const Model nominal = nominalFor(args, calibrated, "accuracy", "calibrated");
  std::optional<TrueRobot> truth;
  if (args.has("truth")) truth = loadTruthFile(args.get("truth", ""));
  if (args.has("cell") + args.has("poses") + args.has("whole-range") > 1)
    throw UsageError("give one of --cell, --poses and --whole-range");
  CompensationOptions options;
  if (args.has("tool")) {
    const auto tool = parsePoseText(args.get("tool", ""));
    if (!tool) throw UsageError("--tool: expected x,y,z,rz,ry,rx (mm, deg)");
    options.tool = *tool;
  }
  const Compensator compensator(nominal, calibrated, options);

  const TrueRobot* true_robot = truth ? &*truth : nullptr;
  AccuracyReport report;
  if (args.has("whole-range")) {
    const long count = args.integer("whole-range", 200);
    if (count < 1 || count > 100000) throw UsageError("--whole-range: 1 to 100000 joint vectors");
    report = assessAccuracyAtJoints(
        compensator, wholeRangeJoints(compensator.nominalArm(), static_cast<std::size_t>(count)),
        true_robot);
    report.poses_from =
        "the arm's whole range: " + std::to_string(count) + " joint vectors within its limits";
  } else if (args.has("poses")) {
    const TargetFile file = loadTargetsFile(args.get("poses", ""));
    std::vector<Eigen::Isometry3d> poses;
    std::vector<std::optional<ArmConfig>> configs;  // the config column's, as compensate's
    std::vector<JointsDeg> joints;
    for (const Target& t : file.targets) {
      if (!t.pose) {
        joints.push_back(*t.nominal_joints);
        continue;
      }
      poses.push_back(*t.pose);
      configs.push_back(t.config);
    }
    report = file.joints_form ? assessAccuracyAtJoints(compensator, joints, true_robot)
                              : assessAccuracy(compensator, poses, true_robot, configs);
    report.poses_from = args.get("poses", "");
  } else {
    const CellConfig cell = args.has("cell") ? loadCellFile(args.get("cell", "")) : CellConfig{};
    report =
        assessAccuracy(compensator, workVolumePoses(cell.work_volume, compensator), true_robot);
    report.poses_from = args.has("cell") ? "work_volume of " + args.get("cell", "")
                                         : std::string("the reference cell's work volume");
  }
  if (args.has("svg")) writeTextFileAtomic(args.get("svg", ""), accuracySvg(report));
  if (args.flag("json")) {
    std::printf("%s\n", accuracyJson(report, true).dump().c_str());
  } else {
    std::fputs(accuracyText(report).c_str(), stdout);
    if (args.has("svg")) std::printf("wrote %s\n", args.get("svg", "").c_str());
  }
  return 0;
}

const RegisterCommand registered({"accuracy",
                                  "accuracy over the work volume, nominal and compensated", run});

}  // namespace
}  // namespace robocal::cli
