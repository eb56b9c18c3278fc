// The files of `robocal compensate` (docs/compensation.md):
// - the targets CSV, in one of two forms found by its header: desired tool poses
//   (x_mm,y_mm,z_mm,rz_deg,ry_deg,rx_deg, optional config) or a program's nominal joints
//   (j1..j6, controller readings in deg); both take an optional name column;
// - the output: CSV (name, j1..j6, a1..a6, predicted_error_mm, status, config, note), VAL II
//   precision points, `#PPOINT(j1, ..., j6)` or `DO MOVE #PPOINT(...)` lines, each after a `;`
//   comment naming its target (the name column, else "line N" of the targets file), or a location
//   file a controller loads: a V+ `.LOCATIONS` or an AS `.JOINTS` block of `#name v1 ... v6` lines
//   (the layouts of formats/program.hpp, so parseProgram reads them back), each target under its
//   name (else `p<line>`), its pre-point as `#name_pre`.
// Malformed rows are FormatError naming file:line and the problem.
#pragma once

#include <robocal/compensation/compensate.hpp>
#include <robocal/formats/error.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace robocal {

struct Target {
  std::string name;                         // "" when the file has no name column
  std::optional<Eigen::Isometry3d> pose;    // the pose form: desired tool pose (world frame)
  std::optional<ArmConfig> config;          // the pose form's optional config column
  std::optional<JointsDeg> nominal_joints;  // the joints form
  int line = 0;                             // 1-based line in the file
  std::array<double, 6> written{};          // the row's six numbers as the file has them
};

struct TargetFile {
  std::string source;
  bool has_names = false;
  bool joints_form = false;
  std::vector<Target> targets;
};

TargetFile parseTargets(const std::string& text, const std::string& source = "targets");
TargetFile loadTargetsFile(const std::string& path);
// Why the file's numbers look like another unit than the format's, in words (joints in radians,
// positions in metres), with the fix; nullopt when they look right.
std::optional<std::string> targetsUnitsProblem(const TargetFile& file);

// Compensates one target (the form decides which Compensator call).
CompensatedTarget compensateTarget(const Compensator& compensator, const Target& target);

enum class OutputFormat { kCsv, kVal2Points, kVal2Moves, kVplusLocations, kAsJoints };
// "csv", "val2", "val2-move", "vplus-locations", "as-joints"; nullopt for another word.
std::optional<OutputFormat> parseOutputFormat(const std::string& word);

// The output text. Rows whose status is unreachable or outside_limits carry no joints (CSV: empty
// j1..j6; VAL II: a `;` comment line), so that nothing that cannot be reached is ever commanded.
// With an approach (`approach_deg` > 0, Compensator::approachDeg), CSV rows carry each joint's
// direction into the target (a1..a6, +1: up), and the VAL II outputs put the pre-point before
// each target (a header comment says so); a location file defines it as its own location.
// A location file needs names a controller takes (a letter, then letters, digits, '.' or '_'),
// each once: another is a FormatError naming the targets file's line, and nothing is returned.
std::string formatCompensated(const TargetFile& file, const std::vector<CompensatedTarget>& results,
                              OutputFormat format, double approach_deg = 0);

}  // namespace robocal
