// robocal import: a nominal model from another format. So far one: a URDF serial chain
// (formats/include/robocal/formats/urdf_import.hpp, docs/import.md).
#include "args.hpp"

#include <robocal/formats/error.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/urdf_import.hpp>

#include <cstdio>
#include <filesystem>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal import --urdf FILE --out MODEL [--base LINK] [--tip LINK]
                      [--fixtures MODEL] [--name NAME]

Reads a serial chain of six revolute (or continuous) joints from a URDF file and writes it as a
robocal nominal model: each joint's axis, any direction, becomes the z axis of its model frame;
fixed joints are merged into the link transforms; offsets 0, gains 1, limits from the URDF
(continuous joints -360 to 360 deg); meters and radians become mm and degrees. The model's
forward kinematics are the URDF's. docs/import.md has the frames and how it is tested.

The balls on the tool and the chucks on the table belong to the cell, not the robot: they are
read from links ball1..ball3 below the tip and chuck1..chuck3 below the base when the URDF has
them (as robocal export --urdf writes them), else taken from --fixtures.

  --urdf FILE             URDF file to read                                        required
  --out MODEL             model file to write (replaced whole, never half-written) required
  --base LINK             the chain's first link     [chuck_fixture if present, else the root]
  --tip LINK              the chain's last link [ball_fixture if present, else the link the
                          sixth joint moves]
  --fixtures MODEL        take the balls and chucks from this model file   [from the URDF]
  --name NAME             the model's name                        [<robot name> (URDF)]

exit status: 0 written, 1 an unreadable or unsuitable URDF or an unwritable file, 2 a usage
error (also: no fixtures in the URDF and no --fixtures)
)";

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"urdf", "out", "base", "tip", "fixtures", "name"}, {"help"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional().front() + "'");
  const std::string urdf_path = args.required("urdf");
  const std::string out = args.required("out");
  for (const char* key : {"base", "tip", "name", "fixtures"})
    if (args.has(key) && args.get(key, "").empty())
      throw UsageError(std::string("--") + key + " must not be empty");
  std::error_code ec;
  if (std::filesystem::equivalent(out, urdf_path, ec))
    throw UsageError("--out " + out + " is the URDF file itself");

  UrdfImportOptions options;
  options.base_link = args.get("base", "");
  options.tip_link = args.get("tip", "");
  options.name = args.get("name", "");
  UrdfImport imported = urdfToModel(readTextFile(urdf_path), urdf_path, options);
  Model& model = imported.model;
  std::string fixtures_from = "the URDF's ball and chuck links";
  if (args.has("fixtures")) {
    const Model fixtures = loadModelFile(args.get("fixtures", ""));
    model.balls_mm = fixtures.balls_mm;
    model.chucks_mm = fixtures.chucks_mm;
    fixtures_from = args.get("fixtures", "");
  } else if (!imported.fixtures_found) {
    throw UsageError(urdf_path +
                     " has no links ball1..ball3 below the tip and chuck1..chuck3 below the "
                     "base: give the cell's balls and chucks with --fixtures MODEL (a model file "
                     "whose balls and chucks are taken)");
  }
  saveModelFile(out, model);

  std::printf("wrote %s: \"%s\", six joints from link %s to link %s\n", out.c_str(),
              model.name.c_str(), imported.base_link.c_str(), imported.tip_link.c_str());
  for (const JointParams& j : model.joints)
    std::printf("  joint %-20s %9.3f .. %8.3f deg\n", j.name.c_str(), j.min_deg, j.max_deg);
  if (!imported.fixed_joints.empty()) {
    std::printf("fixed joints merged into the links:");
    for (const std::string& f : imported.fixed_joints) std::printf(" %s", f.c_str());
    std::printf("\n");
  }
  std::printf("balls and chucks from %s\n", fixtures_from.c_str());
  return 0;
}

const RegisterCommand registered({"import", "read a nominal model from a URDF file", run});

}  // namespace
}  // namespace robocal::cli
