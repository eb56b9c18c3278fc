#include <robocal/sim/measurements.hpp>

#include <robocal/kinematics/ik.hpp>
#include <robocal/kinematics/kinematics.hpp>
#include <robocal/kinematics/units.hpp>

#include <cmath>
#include <optional>

namespace robocal {
namespace {

constexpr double kWristMarginDeg = 5.0;        // stay this far from the wrist singularity (J5 = 0)
constexpr double kLimitMarginDeg = 5.0;        // and this far inside the joint limits
constexpr double kBarToolClearanceDeg = 70.0;  // angle kept between the bar and the tool axis

// Grid size close to `points` with about 1.25 longitudes per latitude.
std::pair<int, int> gridSize(int points) {
  const int lats = std::max(1, static_cast<int>(std::lround(std::sqrt(points / 1.25))));
  const int lons = (points + lats - 1) / lats;
  return {lats, lons};
}

Eigen::Matrix3d toolOrientation(const Eigen::Vector3d& approach, double roll_rad) {
  const Eigen::Vector3d z = approach.normalized();
  Eigen::Vector3d ref = std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Vector3d x = (ref - ref.dot(z) * z).normalized();
  x = Eigen::AngleAxisd(roll_rad, z) * x;
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

}  // namespace

Model perturbModel(const Model& nominal, const PerturbationSigmas& s, std::mt19937_64& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  ParamVector p = toParams(nominal);
  const ParamVector sigma =
      paramSigmas(s.translation_mm, s.link_angle_deg, s.joint_offset_deg, s.gain);
  for (int i = 0; i < kParamCount; ++i) p[i] += sigma[i] * unit(rng);
  Model truth = withParams(nominal, p);
  truth.name = nominal.name + " (simulated truth)";
  truth.compliance.reset();  // a true robot twists by its realism (true_robot.hpp), not its model
  return truth;
}

std::vector<ShellRequest> shellRequests(const std::vector<Connection>& connections,
                                        const std::vector<double>& extensions_mm, int points) {
  std::vector<ShellRequest> out;
  for (double extension : extensions_mm)
    for (const Connection& c : connections) {
      ShellRequest req;
      req.connection = c;
      req.radius_mm = kDefaultBarMm + extension;
      req.extension_mm = extension;
      req.points = points;
      req.shell = static_cast<int>(out.size()) + 1;
      out.push_back(req);
    }
  return out;
}

ShellPoses shellPoses(const Model& model, const ShellRequest& req, std::mt19937_64& rng) {
  const Kinematics kin(model);
  const Eigen::Vector3d chuck = model.chucks_mm[req.connection.chuck_index];
  const Eigen::Vector3d ball_in_tool = model.balls_mm[req.connection.ball_index];
  const Eigen::Vector3d shoulder = kin.chainFrames(JointsDeg::Zero())[0].translation();
  std::uniform_real_distribution<double> roll_dist(-180.0, 180.0), tilt_dist(-45.0, 45.0);

  const auto [lats, lons] = gridSize(req.points);
  ShellPoses out;
  JointsDeg previous = JointsDeg::Zero();
  bool have_previous = false;
  int remaining = req.points;
  for (int i = 0; i < lats && remaining > 0; ++i) {
    const double lat_deg = lats == 1 ? 45.0 : 10.0 + 70.0 * i / (lats - 1);
    for (int k = 0; k < lons && remaining > 0; ++k, --remaining) {
      // Alternate the direction of travel on each latitude so neighbours stay close.
      const int kk = (i % 2 == 0) ? k : lons - 1 - k;
      const double lon_deg = 360.0 * kk / lons;
      const double lat = lat_deg * kRadPerDeg, lon = lon_deg * kRadPerDeg;
      const Eigen::Vector3d ball =
          chuck + req.radius_mm * Eigen::Vector3d(std::cos(lat) * std::cos(lon),
                                                  std::cos(lat) * std::sin(lon), std::sin(lat));
      // The tool reaches from the robot toward the ball, tilted down, and keeps its body away
      // from the bar (the tool body lies along -approach from the ball).
      Eigen::Vector3d approach = (ball - shoulder).normalized() + Eigen::Vector3d(0, 0, -1.0);
      approach.normalize();
      const Eigen::Vector3d to_chuck = (chuck - ball).normalized();
      const double min_cos = std::cos(kBarToolClearanceDeg * kRadPerDeg);
      for (int n = 0; n < 20 && (-approach).dot(to_chuck) > min_cos; ++n)
        approach = (approach + 0.2 * to_chuck).normalized();
      const Eigen::Vector3d tilt_axis = approach.cross(Eigen::Vector3d::UnitZ()).normalized();
      if (tilt_axis.allFinite())
        approach = Eigen::AngleAxisd(tilt_dist(rng) * kRadPerDeg, tilt_axis) * approach;

      std::optional<JointsDeg> found;
      for (int attempt = 0; attempt < 6 && !found; ++attempt) {
        Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
        target.linear() = toolOrientation(approach, roll_dist(rng) * kRadPerDeg);
        target.translation() = ball - target.linear() * ball_in_tool;
        std::vector<JointsDeg> seeds;
        if (have_previous) seeds.push_back(previous);
        const double azimuth =
            std::atan2(ball.y() - shoulder.y(), ball.x() - shoulder.x()) / kRadPerDeg;
        for (double wrist : {45.0, -45.0}) {
          JointsDeg s;
          s << azimuth, 30.0, -170.0, 0.0, wrist, 0.0;
          seeds.push_back(s);
        }
        for (const JointsDeg& seed : seeds) {
          const auto q = solveIk(kin, target, seed);
          if (q && withinLimits(model, *q, kLimitMarginDeg) &&
              std::abs((*q)[4]) > kWristMarginDeg) {
            found = q;
            break;
          }
        }
      }
      if (!found) {
        ++out.dropped;
        continue;
      }
      previous = *found;
      have_previous = true;
      out.poses.push_back({lat_deg, lon_deg, *found, {}});
    }
  }
  return out;
}

std::vector<Sample> measureShell(const Model& truth, const ShellRequest& req,
                                 const std::vector<ShellPose>& poses, const MeasurementNoise& noise,
                                 std::mt19937_64& rng) {
  RunTrack track;
  return measureShell(TrueRobot{truth, Realism::ideal()}, req, poses, noise, rng, track);
}

void RunTrack::moveTo(const JointsDeg& q_deg) {
  if (started) approach = approachOf(last_deg, q_deg, approach);
  started = true;
  last_deg = q_deg;
}

std::vector<Sample> measureShell(const TrueRobot& truth, const ShellRequest& req,
                                 const std::vector<ShellPose>& poses, const MeasurementNoise& noise,
                                 std::mt19937_64& rng, RunTrack& track) {
  const bool ideal = truth.realism.isIdeal();
  std::optional<Kinematics> fixed;
  if (ideal || truth.realism.warmup_k == 0) fixed.emplace(truth.model);
  std::normal_distribution<double> length_noise(0.0, noise.length_sigma_mm);
  std::vector<Sample> samples;
  samples.reserve(poses.size());
  const Connection& c = req.connection;
  const Eigen::Vector3d& ball = truth.model.balls_mm[c.ball_index];
  const Eigen::Vector3d& chuck = truth.model.chucks_mm[c.chuck_index];
  for (const ShellPose& pose : poses) {
    for (const JointsDeg& via : pose.vias_deg) track.moveTo(via);
    track.moveTo(pose.joints_deg);
    track.minutes += track.minutes_per_point;
    double length_mm = 0;
    if (ideal) {
      length_mm = fixed->barLength(pose.joints_deg, ball, chuck);
    } else {
      const JointsDeg q = truth.effectiveReadings(pose.joints_deg, track.approach);
      const double distance_mm =
          fixed ? fixed->barLength(q, ball, chuck)
                : Kinematics(truth.modelAt(track.minutes)).barLength(q, ball, chuck);
      length_mm = truth.measuredLength(distance_mm, req.radius_mm);
    }
    Sample s = makeSample(req.shell, c, req.extension_mm, pose.lat_deg, pose.lon_deg,
                          pose.joints_deg, length_mm);
    s.time_s = track.minutes * 60;
    if (noise.length_sigma_mm > 0) s.length_mm += length_noise(rng);
    if (noise.joint_quantum_deg > 0)
      for (int j = 0; j < kJointCount; ++j)
        s.joints_deg[j] =
            std::round(pose.joints_deg[j] / noise.joint_quantum_deg) * noise.joint_quantum_deg;
    samples.push_back(std::move(s));
  }
  return samples;
}

}  // namespace robocal
