// One ball-bar measurement: which ball and chuck, the joint readings, the absolute bar length.
// Plain data; formats/ reads and writes it as CSV (docs/samples-format.md).
#pragma once

#include <robocal/kinematics/model.hpp>

#include <optional>
#include <string>
#include <vector>

namespace robocal {

struct Sample {
  int shell = 0;
  int ball_index = 0;   // 0-based here, 1-based in files
  int chuck_index = 0;  // 0-based here, 1-based in files
  double extension_mm = 0;
  double lat_deg = 0;
  double lon_deg = 0;
  JointsDeg joints_deg = JointsDeg::Zero();
  double length_mm = 0;  // absolute ball-centre to chuck-centre distance
  // When it was measured, seconds on the run's clock (only differences count: the daemon writes
  // Unix time, `robocal simulate` the simulated robot time); absent when not known.
  std::optional<double> time_s;
  // How the point was reached: each joint rose into it by this much (deg) from a pre-point, so
  // backlash sat on one side (the plan's motion.approach_deg); 0 when it came as the path went.
  // Absent when the file does not say (written before the record existed).
  std::optional<double> approach_deg;
  std::string source;   // file it came from ("" when made in memory)
  int source_line = 0;  // 1-based line in that file (0 when made in memory)
};

// A ball-chuck pair, 0-based. Written "B1C2" (1-based) at the interfaces.
struct Connection {
  int ball_index = 0;
  int chuck_index = 0;
  friend bool operator==(const Connection&, const Connection&) = default;
};

std::string connectionName(const Connection& c);
// "B1C1,B2C3": the names joined with commas, as parseConnections reads them.
std::string connectionList(const std::vector<Connection>& connections);
// "all" or a comma list like "B1C1,B2C3"; throws std::invalid_argument naming the bad item.
std::vector<Connection> parseConnections(const std::string& text);
std::vector<Connection> allConnections();

// A sample of shell `shell`: the bar of extension `extension_mm` between `connection`'s ball and
// chuck, the robot at `joints_deg`, the bar `length_mm` long, at the point (lat_deg, lon_deg) of
// the shell. The planner (predicted samples), the simulator and the daemon make them alike.
inline Sample makeSample(int shell, const Connection& connection, double extension_mm,
                         double lat_deg, double lon_deg, const JointsDeg& joints_deg,
                         double length_mm) {
  Sample s;
  s.shell = shell;
  s.ball_index = connection.ball_index;
  s.chuck_index = connection.chuck_index;
  s.extension_mm = extension_mm;
  s.lat_deg = lat_deg;
  s.lon_deg = lon_deg;
  s.joints_deg = joints_deg;
  s.length_mm = length_mm;
  return s;
}

}  // namespace robocal
