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
                        [--cell cell.json | --poses FILE] [--tool x,y,z,rz,ry,rx]
                        [--json] [--svg FILE]

Tool position and orientation error over the work volume: the calibrated model's predicted
1-sigma error (from its covariance; needs no truth) and, for a simulation's true robot, the
error of the true robot commanded with the nominal joints and with the compensated joints
(RMS, p95, max). The poses are the cell file's work_volume (docs/compensation.md; without
--cell and --poses, the reference cell's) or a targets file (robocal compensate's forms).

  --calibrated FILE     the calibrated model                                      required
  --nominal FILE        the controller's model: only a check, refused when it differs from
                        the one recorded in CALIBRATED   [the recorded one, else the PUMA 560]
  --truth FILE          a simulation's true robot (robocal simulate --truth-out); with its
                        realism, judged warm, approaching in +, with its payload
  --cell FILE           cell file: its work_volume section
  --poses FILE          targets CSV instead of the work volume
  --tool X,Y,Z,RZ,RY,RX tool centre point in the ball fixture's frame (mm, deg)  [0,...]
  --json                one JSON object (with every pose) instead of text
  --svg FILE            write a map of the error over the volume (seen from above)

exit status: 0 done, 1 an unreadable input, 2 a usage error
)";

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"nominal", "calibrated", "truth", "cell", "poses", "tool", "svg"},
                  {"json", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const Model calibrated = loadModelFile(args.required("calibrated"));
  const Model nominal = nominalFor(args, calibrated, "accuracy", "calibrated");
  std::optional<TrueRobot> truth;
  if (args.has("truth")) truth = loadTruthFile(args.get("truth", ""));
  if (args.has("cell") && args.has("poses")) throw UsageError("give --cell or --poses, not both");
  CompensationOptions options;
  if (args.has("tool")) {
    const auto tool = parsePoseText(args.get("tool", ""));
    if (!tool) throw UsageError("--tool: expected x,y,z,rz,ry,rx (mm, deg)");
    options.tool = *tool;
  }
  const Compensator compensator(nominal, calibrated, options);

  std::vector<Eigen::Isometry3d> poses;
  std::string from;
  if (args.has("poses")) {
    const TargetFile file = loadTargetsFile(args.get("poses", ""));
    for (const Target& t : file.targets)
      poses.push_back(t.pose ? *t.pose : compensator.nominalToolPose(*t.nominal_joints));
    from = args.get("poses", "");
  } else {
    const CellConfig cell = args.has("cell") ? loadCellFile(args.get("cell", "")) : CellConfig{};
    poses = workVolumePoses(cell.work_volume, compensator);
    from = args.has("cell") ? "work_volume of " + args.get("cell", "")
                            : std::string("the reference cell's work volume");
  }
  AccuracyReport report = assessAccuracy(compensator, poses, truth ? &*truth : nullptr);
  report.poses_from = from;
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
