// robocal export: a model in another format for other tools: URDF
// (formats/include/robocal/formats/urdf.hpp), the frames as JSON and a standard DH table
// (formats/include/robocal/formats/frames.hpp); docs/export.md.
#include "args.hpp"

#include <robocal/formats/frames.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/urdf.hpp>

#include <charconv>
#include <cstdio>
#include <filesystem>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal export --urdf --model MODEL --out FILE [--name ROBOT]
                      [--velocity-deg-per-s V] [--effort-nm E]
       robocal export --frames | --dh --model MODEL --out FILE [--parallel-tolerance-deg T]

Writes the model as a URDF file for tools that read URDF (ROS, visualizers, planners): six
revolute joints about their z axes, from the link chuck_fixture (the model's global frame, the
chuck fixture's) to ball_fixture (the frame of the tool balls), with fixed links for the three
balls and the three chucks. Joint k's origin holds the link transform before it and its zero
offset; meters and radians. The URDF joint value is the controller's reading (radians) times
the joint's gain: URDF cannot hold a gain, so the gains are stated in a comment at the top of
the file and printed here. With gains of 1 the joint value is the reading. The exact path stays
`robocal compensate` with the model file (docs/compensation.md). docs/export.md has the frames
and how the export is tested.

URDF requires each joint's rated velocity and effort, and a velocity of 0 is a joint a planner
cannot move: they come from the model's joints (velocity_deg_per_s, effort_nm), and for joints
the model has none of, from --velocity-deg-per-s and --effort-nm (take them from the robot's
data sheet); without either the export is refused, naming the joints.

--frames writes the model's chain as JSON matrices and quaternions (mm, deg) with each joint's
axis at zero readings, the balls, the chucks and the DH table: for tools that multiply frames
without robocal's conventions. --dh writes a standard DH table (CSV with a commented base and
tool transform) for analytic-IK code. DH holds four numbers a link where the model has six: it is
exact except where consecutive axes are within --parallel-tolerance-deg of parallel (a PUMA's
joints 2 and 3), which it takes as parallel; the error that costs against the model, over 1,000
joint vectors within the limits, is printed and written with the table. Both leave out gravity
compliance (a rigid arm).

  --urdf                  write URDF                                     one of the three
  --frames                write the frames as JSON                       one of the three
  --dh                    write a standard DH table (CSV)                one of the three
  --model FILE            model to export (model format)                          required
  --out FILE              file to write (replaced whole, never half-written)      required
  --name ROBOT            the robot's name in the URDF       [from the model's name]
  --velocity-deg-per-s V  rated joint speed for joints the model has none of  [the model's]
  --effort-nm E           rated joint torque for joints the model has none of [the model's]
  --parallel-tolerance-deg T  axes this close to parallel are parallel in DH  [0.5]

exit status: 0 written, 1 an unreadable model or an unwritable file, 2 a usage error
)";

// A positive number option, 0 when absent.
double positiveArg(const Args& args, const char* key) {
  const double v = args.number(key, 0);
  if (args.has(key) && !(v > 0))
    throw UsageError(std::string("--") + key + " expects a positive number, not '" +
                     args.get(key, "") + "'");
  return v;
}

// A gain as the file's comment states it: the fewest digits that read back as the same double.
std::string shortest(double value) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

// --frames or --dh.
int writeFrames(const Args& args, const std::string& model_path, const std::string& out) {
  const double tolerance_deg = args.number("parallel-tolerance-deg", kDhParallelToleranceDeg);
  if (!(tolerance_deg >= 0 && tolerance_deg < 90))
    throw UsageError("--parallel-tolerance-deg expects degrees from 0 to 90, not '" +
                     args.get("parallel-tolerance-deg", "") + "'");
  const Model model = loadModelFile(model_path);
  const DhTable dh = dhFromModel(model, tolerance_deg);
  const std::string source = std::filesystem::absolute(model_path).lexically_normal().string();
  writeTextFileAtomic(out, args.flag("frames") ? modelFramesJson(model, dh, source).dump(1) + "\n"
                                               : dhTableCsv(model, dh, source));
  std::printf("wrote %s: %s of \"%s\"\n", out.c_str(),
              args.flag("frames") ? "the frames and the DH table" : "the DH table",
              model.name.c_str());
  std::printf("DH table: %s\n", dhErrorSummary(dh).c_str());
  if (dh.max_position_error_mm > 1e-6)
    std::printf(
        "the table is not exact: use the model file (robocal compensate) or --frames where that "
        "error matters; --parallel-tolerance-deg 0 makes it exact with far-away frames\n");
  return 0;
}

int run(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"model", "out", "name", "velocity-deg-per-s", "effort-nm", "parallel-tolerance-deg"},
      {"urdf", "frames", "dh", "help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  const int formats = args.flag("urdf") + args.flag("frames") + args.flag("dh");
  if (formats != 1)
    throw UsageError(formats == 0 ? "say which format to write: --urdf, --frames or --dh"
                                  : "one format at a time: --urdf, --frames or --dh");
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional().front() + "'");
  const std::string model_path = args.required("model");
  const std::string out = args.required("out");
  if (args.has("name") && args.get("name", "").empty())
    throw UsageError("--name must not be empty");
  std::error_code ec;
  if (std::filesystem::equivalent(out, model_path, ec))
    throw UsageError("--out " + out + " is the model file itself");

  if (!args.flag("urdf")) {
    for (const char* key : {"name", "velocity-deg-per-s", "effort-nm"})
      if (args.has(key)) throw UsageError(std::string("--") + key + " is for --urdf only");
    return writeFrames(args, model_path, out);
  }
  if (args.has("parallel-tolerance-deg"))
    throw UsageError("--parallel-tolerance-deg is for --frames and --dh only");
  const Model model = loadModelFile(model_path);
  UrdfOptions options;
  options.robot_name = args.get("name", urdfRobotName(model));
  options.source = std::filesystem::absolute(model_path).lexically_normal().string();
  options.velocity_deg_per_s = positiveArg(args, "velocity-deg-per-s");
  options.effort_nm = positiveArg(args, "effort-nm");
  std::string missing;
  urdfLimits(model, options, &missing);
  if (!missing.empty()) {
    throw UsageError(
        "URDF needs each joint's rated velocity and effort, and " + model_path +
        " has none for: " + missing +
        ". Give them with --velocity-deg-per-s and --effort-nm (from the robot's data sheet), "
        "or add velocity_deg_per_s and effort_nm to the model's joints");
  }
  writeTextFileAtomic(out, modelToUrdf(model, options));

  const auto joints = urdfJointNames(model);
  std::printf("wrote %s: robot \"%s\", revolute joints %s..%s from %s to %s\n", out.c_str(),
              options.robot_name.c_str(), joints.front().c_str(), joints.back().c_str(),
              kUrdfBaseLink, kUrdfBallFixtureLink);
  std::printf("joint gains (URDF cannot hold them; also in the file's comment):");
  bool unit_gains = true;
  for (int j = 0; j < kJointCount; ++j) {
    std::printf(" %s %s", joints[j].c_str(), shortest(model.joints[j].gain).c_str());
    unit_gains = unit_gains && model.joints[j].gain == 1.0;
  }
  std::printf("\n");
  if (unit_gains)
    std::printf("every gain is 1: the URDF joint value is the controller's reading in radians\n");
  else
    std::printf(
        "some gains are not 1: for exact forward kinematics the URDF joint value must be\n"
        "reading * gain (radians), not the reading; robocal compensate with the model file stays "
        "the exact path\n");
  return 0;
}

const RegisterCommand registered({"export",
                                  "write a model as URDF, frames JSON or a DH table for other "
                                  "tools",
                                  run});

}  // namespace
}  // namespace robocal::cli
