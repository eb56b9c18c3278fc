// The cell file's settings (docs/cell-format.md): the bar, the connections and their order, the
// shell grid, the tool-orientation policy, the safety margins, the motion and the model
// uncertainty the plan's deflection forecast assumes. Plain data in mm, deg and s; no I/O.
#pragma once

#include <robocal/kinematics/sample.hpp>

#include <array>
#include <string>
#include <vector>

namespace robocal {

struct BarSettings {
  double nominal_length_mm = 150;  // ball centre to chuck centre at zero deflection
  std::vector<double> extension_lengths_mm = {0, 150};  // one set of shells per extension
  double max_deflection_mm = 2.0;                       // the LVDT reads +/- this much
};

struct GridSettings {
  double latitude_first_deg = 10, latitude_last_deg = 80, latitude_step_deg = 10;
  double longitude_first_deg = 0, longitude_step_deg = 30;  // around the whole circle
};

// The tool axis (flange z) at a data point: it reaches away from joint 1's axis, `pitch` below
// the horizontal and turned `yaw` out of the arm's vertical plane (which keeps joint 5 away from
// zero); both vary over the shell by their amplitudes, and the tool rolls about its axis by
// roll +/- roll_variation. When the bar would come closer than min_bar_tool_angle_deg to the
// tool's axis, the axis is turned toward the chuck until it does not.
struct ToolOrientationPolicy {
  double approach_pitch_deg = 45;
  double pitch_variation_deg = 15;
  double approach_yaw_deg = 35;
  double yaw_variation_deg = 15;
  double roll_deg = 0;
  double roll_variation_deg = 60;
  double min_bar_tool_angle_deg = 70;
};

struct SafetyMargins {
  double joint_limit_deg = 5;            // kept inside every joint limit
  double wrist_singularity_deg = 10;     // axes of joints 4 and 6 from aligned (Arm's margins)
  double elbow_singularity_deg = 10;     // elbow bend from the straight arm
  double shoulder_singularity_mm = 100;  // wrist point from the plane of joints 1 and 2's axes
  double table_clearance_mm = 30;        // flange and wrist centre above the chucks' plane z = 0
  double bar_clearance_mm = 40;          // flange and wrist centre from the bar (chuck to ball)
};

struct MotionSettings {
  double joint_speed_deg_per_s = 20;  // speed of the fastest joint on a joint-interpolated move
  double move_overhead_s = 0.5;       // per move: acceleration, settling of the command, polling
  double settle_s = 2.0;              // dwell at each data point before recording
  double swap_s = 60;                 // the operator's time to move the bar to a new connection
  double via_tolerance_mm = 0.5;      // nominal radial deviation allowed along every segment
  double sample_step_mm = 0.5;        // ball spacing when segments are checked (<= 1 mm)
  // When positive, every data point is reached from a pre-point this far below it in every joint
  // (one joint further, so that the ball stays on the shell): each joint moves into every point
  // in the positive direction and a real arm's gear backlash is the same at all of them, absorbed
  // by the joint offsets instead of scattering the fit. At least the backlash (0.005-0.02 deg);
  // 0.02 halved the realistic truth's extra error (docs/accuracy.md). Off (0) by default until the
  // optimal and check plans are tuned with it (they lose points and minutes to it).
  double approach_deg = 0;
  // The arm moves through the vias between two points without stopping (the controller blends a
  // program's moves: val.path_* in the drivers config, docs/cell-time.md): a via costs its travel,
  // not a stop. Only where the controller is known to do it; robocal-cellsim models it. Off: every
  // via is a DO MOVE that stops (move_overhead_s each).
  bool through_vias = false;
  // How far the controller blends a corner, in degrees of the largest joint's travel (the window
  // its path is averaged over: robocal/kinematics/path_motion.hpp; robocal-cellsim's --blend-deg).
  // Moving through vias, the planner checks the blended path within via_tolerance_mm and stops at
  // a via where it is not. An assumption until measured on the controller (docs/cell-time.md).
  double blend_deg = 2;
  // When positive, after every this many points of a shell the point before the last is measured
  // again (its revisit, reached the same way): the revisits measure the bar's own noise, so a fit
  // judges its residual against it (solver/adequacy.hpp) instead of assuming it. 0: none.
  int revisit_every = 0;
  // When positive, a shell's first data point (its reference pose) is measured again whenever this
  // many minutes of planned robot time have passed since it last was, and once more at the shell's
  // end: the change of its reading over time is the drift of the robot and the bar (warm-up),
  // reported by every fit (solver/drift.hpp). 0: none.
  double reference_every_min = 0;
};

// Model error assumed by the plan's forecast of the bar's deflection: Gaussian perturbations of
// the 54 parameters (as `robocal simulate` makes its true robots), `models` of them.
struct ModelUncertainty {
  double translation_sigma_mm = 0.2;
  double link_angle_sigma_deg = 0.02;
  double joint_offset_sigma_deg = 0.05;
  double gain_sigma = 0.0005;
  int models = 20;
  int seed = 1;
};

// Where the user works (docs/compensation.md): tool poses drawn uniformly from a box in the world
// (chuck fixture) frame and ranges of the tool's ZYX angles, `poses` of them that the nominal
// model reaches, from `seed`. Accuracy is judged over these poses (robocal accuracy, the fit's
// report). The defaults cover the reference cell's working area near the chucks, tool pointing
// away from the robot and down as in the calibration's shells.
struct WorkVolume {
  std::array<double, 3> box_min_mm = {-250, -250, 150};
  std::array<double, 3> box_max_mm = {150, 250, 400};
  std::array<double, 2> rz_range_deg = {-30, 30};
  std::array<double, 2> ry_range_deg = {120, 150};
  std::array<double, 2> rx_range_deg = {-30, 30};
  int poses = 200;
  int seed = 1;
};

struct CellConfig {
  std::string name;
  BarSettings bar;
  std::vector<Connection> connections = allConnections();  // in the order they are run
  GridSettings grid;
  ToolOrientationPolicy tool;
  // "auto" (per shell, the configuration that reaches the most points) or a name such as
  // "right-up-noflip" (see armConfigName).
  std::string arm_configuration = "auto";
  double connect_lat_deg = 90, connect_lon_deg = 0;  // where the operator attaches the bar
  SafetyMargins margins;
  MotionSettings motion;
  ModelUncertainty uncertainty;
  WorkVolume work_volume;
};

// Latitudes and longitudes of the grid (deg), in increasing order; empty when the grid is empty.
std::vector<double> gridLatitudes(const GridSettings& grid);
std::vector<double> gridLongitudes(const GridSettings& grid);

// Throws std::invalid_argument naming the key ("motion.via_tolerance_mm: ...") of the first
// setting that is out of range or inconsistent with the others.
void validateCell(const CellConfig& cell);

}  // namespace robocal
