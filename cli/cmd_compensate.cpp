// robocal compensate: corrected joint readings for target poses or for a program's nominal joints,
// with a calibrated model (compensation/, docs/compensation.md).
#include "args.hpp"
#include "model_args.hpp"

#include <robocal/compensation/targets.hpp>
#include <robocal/formats/model_json.hpp>
#include <robocal/formats/program.hpp>

#include <cstdio>
#include <filesystem>

namespace robocal::cli {
namespace {

constexpr const char* kHelp =
    R"(usage: robocal compensate --model CALIBRATED --targets FILE --out FILE
                          [--nominal NOMINAL] [--tool x,y,z,rz,ry,rx] [--format F]
       robocal compensate --model CALIBRATED --program FILE --dialect as|vplus|val2 --out FILE

Corrected joint readings that put the real robot's tool at each target, computed with the
calibrated model instead of the nominal one the controller uses. Frames (docs/compensation.md):
world = the chuck fixture's frame; tool = the ball fixture's frame (the last link's), times --tool.

The targets CSV (a header row; # comments) takes one of two forms, found by its header:
  x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg   desired tool poses, Trans(x,y,z) Rz Ry Rx; optional
                                         config column (e.g. right-up-noflip)
  j1,j2,j3,j4,j5,j6                      a program's readings (deg) computed with the nominal
                                         model: each is moved to where the program meant it
and an optional name column. Each output row keeps the nominal solution's arm configuration and
joint turns; its status is ok, near_singularity, outside_measured (a joint outside the range the
calibration measured), no_gain (a predicted error above the correction), outside_limits or
unreachable; the last two carry no joints (docs/compensation.md).

  --model FILE          calibrated model (robocal solve --out, or robocald's)          required
  --targets FILE        targets CSV                               required, or --program
  --program FILE        a controller program file: the same program is written with each joint
                        location (a .JOINTS / .LOCATIONS line, a #[...] / #PPOINT(...) literal)
                        corrected and every other byte kept (docs/programs.md); a location that
                        cannot be corrected is kept as it was and named; no pre-points
  --dialect D           the program's language: as (Kawasaki AS), vplus (V+), val2 (VAL II)
  --out FILE            output to write                                                 required
  --nominal FILE        the controller's model: only a check, refused when it differs from the
                        nominal recorded in MODEL                   [the recorded one, else
                        the built-in model of its name; else required]
  --tool X,Y,Z,RZ,RY,RX tool centre point in the ball fixture's frame (mm, deg)       [0,...]
  --approach-deg D      reach each target from a pre-point D deg below it in every joint,
                        as the calibration reached its points (backlash then sits where the
                        calibration measured it); 0: no pre-points   [the model's, else 0]
  --payload-kg M        the work tool's mass (kg) in place of the calibration fixture's, for
                        a model with its compliance (solve --compliance): the joints' twist
                        under it is compensated                 [the model's: the fixture's]
  --payload-com X,Y,Z   its centre of mass, mm in the ball fixture's (last link's) frame
  --format F            csv: name,j1..j6,a1..a6,predicted_error_mm,status,config,note   [csv]
                          (a1..a6: each joint's direction into the target, 1 = up, empty
                          without an approach)
                        val2: one VAL II precision point #PPOINT(j1, ..., j6) per line
                        val2-move: DO MOVE #PPOINT(...) lines
                        (with an approach, each target's pre-point on the line before it;
                        rows that cannot be commanded become ; comment lines)
                        vplus-locations, as-joints: a location file (a V+ .LOCATIONS or a
                        Kawasaki AS .JOINTS block), #name j1 ... j6 per target (its name,
                        else p<line>), its pre-point as #name_pre; rows that cannot be
                        commanded become ; comment lines
  --units-as-given      take the targets' numbers as mm and deg even where they look like
                        metres or radians (every joint or angle within one turn in
                        radians, every position within 3 mm of the origin): refused without

exit status: 0 every target ok, 1 an unreadable input, 2 a usage error,
             3 written, but some targets are not ok (listed on stderr)
)";

constexpr int kExitSomeNotOk = 3;

// --program: the program rewritten with its locations corrected.
int compensateProgram(const Args& args, const Compensator& compensator,
                      const std::string& out_path) {
  const std::string path = args.required("program");
  const auto dialect = parseProgramDialect(args.required("dialect"));
  if (!dialect) throw UsageError("--dialect: expected as, vplus or val2");
  const ProgramFile program = parseProgram(readTextFile(path), *dialect, path);
  std::vector<std::optional<JointsDeg>> corrected;
  size_t not_ok = 0;
  for (const ProgramLocation& loc : program.locations) {
    const Target t{loc.name, std::nullopt, std::nullopt, loc.joints_deg, loc.line};
    const CompensatedTarget r = compensateTarget(compensator, t);
    corrected.push_back(r.hasJoints() ? std::optional<JointsDeg>(r.joints_deg) : std::nullopt);
    if (!r.ok()) {
      ++not_ok;
      std::fprintf(stderr, "%s:%d: %s: %s: %s%s\n", path.c_str(), loc.line, loc.name.c_str(),
                   compensationStatusName(r.status), r.reason.c_str(),
                   r.hasJoints() ? " (corrected)" : " (kept as it was)");
    }
  }
  for (const ProgramReference& u : program.undefined)
    std::fprintf(stderr, "%s:%d: %s is used but not defined in the file: not corrected\n",
                 path.c_str(), u.line, u.name.c_str());
  writeTextFileAtomic(out_path, rewriteProgram(program, corrected));
  std::printf("%s program %s: %zu joint locations, %zu ok, %zu not ok, %zu used but undefined\n",
              programDialectName(*dialect), path.c_str(), program.locations.size(),
              program.locations.size() - not_ok, not_ok, program.undefined.size());
  std::printf("wrote %s (every line but the corrected locations as it was)\n", out_path.c_str());
  return not_ok || !program.undefined.empty() ? kExitSomeNotOk : 0;
}

// Whether two paths name one file (the second need not exist yet); false when either cannot be
// resolved (the write then fails on its own).
bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  const auto ca = std::filesystem::weakly_canonical(a, ec);
  if (ec) return false;
  const auto cb = std::filesystem::weakly_canonical(b, ec);
  return !ec && ca == cb;
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"model", "targets", "out", "nominal", "tool", "format", "approach-deg",
                   "payload-kg", "payload-com", "program", "dialect"},
                  {"help", "units-as-given"});
  if (args.flag("help")) {
    std::fputs(kHelp, stdout);
    return 0;
  }
  if (args.has("program") == args.has("targets"))
    throw UsageError("give --targets (a targets CSV) or --program (a program file), one of them");
  if (args.has("program") && (args.has("format") || args.has("approach-deg")))
    throw UsageError(
        "--format and --approach-deg are for --targets: a program keeps its own "
        "motion");
  if (args.has("dialect") && !args.has("program")) throw UsageError("--dialect is for --program");
  Model calibrated = loadModelFile(args.required("model"));
  const std::string out_path = args.required("out");
  const Model nominal = nominalFor(args, calibrated, "compensate", "model");
  applyPayloadArgs(args, calibrated);
  CompensationOptions options;
  if (args.has("tool")) {
    const auto tool = parsePoseText(args.get("tool", ""));
    if (!tool) throw UsageError("--tool: expected x,y,z,rz,ry,rx (mm, deg)");
    options.tool = *tool;
  }
  if (args.has("program")) {
    if (sameFile(args.get("program", ""), out_path))
      throw UsageError("--out " + out_path +
                       " is the --program file: write elsewhere (nothing "
                       "was written)");
    options.approach_deg = 0;  // no pre-points: the program's own moves decide
    return compensateProgram(args, Compensator(nominal, calibrated, options), out_path);
  }
  const std::string targets_path = args.required("targets");
  options.approach_deg = approachDegArg(args);
  const auto format = parseOutputFormat(args.get("format", "csv"));
  if (!format)
    throw UsageError("--format: expected csv, val2, val2-move, vplus-locations or as-joints");
  if (!calibrated.covariance)
    std::fprintf(stderr,
                 "robocal compensate: note: %s has no covariance: predicted_error_mm stays "
                 "empty (models fitted by this robocal carry one)\n",
                 args.get("model", "").c_str());

  if (sameFile(targets_path, out_path))
    throw UsageError("--out " + out_path +
                     " is the --targets file: write elsewhere (nothing was "
                     "written)");
  const TargetFile file = loadTargetsFile(targets_path);
  if (const auto units = targetsUnitsProblem(file); units && !args.flag("units-as-given"))
    throw UsageError(targets_path + ": " + *units +
                     " (nothing was written; --units-as-given if they are mm and deg after all)");
  const Compensator compensator(nominal, calibrated, options);
  std::vector<CompensatedTarget> results;
  size_t not_ok = 0;
  double worst_shift_deg = 0;
  for (const Target& t : file.targets) {
    results.push_back(compensateTarget(compensator, t));
    const CompensatedTarget& r = results.back();
    if (!r.ok()) {
      ++not_ok;
      std::fprintf(stderr, "%s:%d: %s%s%s: %s\n", targets_path.c_str(), t.line, t.name.c_str(),
                   t.name.empty() ? "" : ": ", compensationStatusName(r.status), r.reason.c_str());
    } else {
      worst_shift_deg =
          std::max(worst_shift_deg, (r.joints_deg - r.nominal_joints_deg).cwiseAbs().maxCoeff());
    }
  }
  writeTextFileAtomic(out_path,
                      formatCompensated(file, results, *format, compensator.approachDeg()));
  std::printf("%zu targets (%s form): %zu ok, %zu not ok; largest joint correction %.4f deg\n",
              results.size(), file.joints_form ? "joints" : "pose", results.size() - not_ok, not_ok,
              worst_shift_deg);
  if (compensator.approachDeg() > 0)
    std::printf("each target from a pre-point %.4g deg below it in every joint%s\n",
                compensator.approachDeg(),
                args.has("approach-deg") ? "" : " (as the calibration reached its points)");
  std::printf("wrote %s\n", out_path.c_str());
  return not_ok ? kExitSomeNotOk : 0;
}

const RegisterCommand registered({"compensate", "corrected joint targets from a calibrated model",
                                  run});

}  // namespace
}  // namespace robocal::cli
