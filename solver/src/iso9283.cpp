#include <robocal/kinematics/kinematics.hpp>
#include <robocal/solver/drift.hpp>
#include <robocal/solver/iso9283.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace robocal {
namespace {

// The standard normal's p quantile (Abramowitz and Stegun 26.2.23, |error| < 4.5e-4).
double normalQuantile(double p) {
  const double q = p < 0.5 ? p : 1 - p;
  const double t = std::sqrt(-2 * std::log(q));
  const double z = t - (2.515517 + 0.802853 * t + 0.010328 * t * t) /
                           (1 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t);
  return p < 0.5 ? -z : z;
}

struct MeanSd {
  double mean = 0, sd = 0;
};

MeanSd meanSd(const std::vector<double>& v) {
  MeanSd m;
  for (double x : v) m.mean += x;
  m.mean /= static_cast<double>(v.size());
  double squares = 0;
  for (double x : v) squares += (x - m.mean) * (x - m.mean);
  m.sd = std::sqrt(squares / static_cast<double>(v.size() - 1));
  return m;
}

// AD (mean of `attained - commanded`) and RD (3 s) with their 95 % intervals.
void figures(const std::vector<double>& errors, IsoFigure& accuracy, IsoFigure& repeatability) {
  const int n = static_cast<int>(errors.size());
  const MeanSd m = meanSd(errors);
  const double half = studentT975(n - 1) * m.sd / std::sqrt(static_cast<double>(n));
  accuracy = {m.mean, m.mean - half, m.mean + half};
  const double dof = n - 1;
  repeatability = {3 * m.sd, 3 * m.sd * std::sqrt(dof / chiSquareQuantile(n - 1, 0.975)),
                   3 * m.sd * std::sqrt(dof / chiSquareQuantile(n - 1, 0.025))};
}

struct PoseReadings {
  const Sample* first = nullptr;
  std::vector<const Sample*> cycles;  // after the warm-up, in order
};

}  // namespace

double studentT975(int dof) {
  static constexpr std::array<double, 30> kTable = {
      12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
      2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
      2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) throw std::invalid_argument("studentT975: dof must be at least 1");
  if (dof <= 30) return kTable[static_cast<size_t>(dof - 1)];
  const double z = 1.959964, v = dof;  // Cornish-Fisher expansion about the normal
  return z + (z * z * z + z) / (4 * v) +
         (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * v * v);
}

double chiSquareQuantile(int dof, double p) {
  if (dof < 1 || !(p > 0 && p < 1))
    throw std::invalid_argument("chiSquareQuantile: dof >= 1 and 0 < p < 1");
  // Wilson and Hilferty: (X / dof)^(1/3) is nearly normal.
  const double v = dof, a = 2 / (9 * v);
  return v * std::pow(std::max(0.0, 1 - a + normalQuantile(p) * std::sqrt(a)), 3);
}

IsoResult assessIsoTest(const Model& model, const std::vector<Sample>& samples, int warmup_cycles) {
  if (samples.empty()) throw std::invalid_argument("no samples");
  const Sample& s0 = samples.front();
  for (const Sample& s : samples)
    if (s.ball_index != s0.ball_index || s.chuck_index != s0.chuck_index ||
        std::abs(s.extension_mm - s0.extension_mm) > 1e-6)
      throw std::invalid_argument(
          "an ISO-style test is measured on one connection and extension; these samples have " +
          connectionName({s0.ball_index, s0.chuck_index}) + " and " +
          connectionName({s.ball_index, s.chuck_index}) + " (line " +
          std::to_string(s.source_line) + ")");
  IsoResult out;
  out.connection = connectionName({s0.ball_index, s0.chuck_index});
  out.extension_mm = s0.extension_mm;
  out.warmup_cycles = warmup_cycles;

  std::vector<PoseReadings> poses;  // in the order first measured
  std::map<SamplePlace, std::size_t> index;
  std::map<SamplePlace, int> seen;
  for (const Sample& s : samples) {
    const SamplePlace place = placeOf(s);
    auto [it, added] = index.try_emplace(place, poses.size());
    if (added) poses.push_back({&s, {}});
    if (seen[place]++ >= warmup_cycles) poses[it->second].cycles.push_back(&s);
  }
  const Kinematics kin(model);
  const auto commanded = [&](const Sample& s) {
    return kin.barLength(s.joints_deg, model.balls_mm[s.ball_index],
                         model.chucks_mm[s.chuck_index]);
  };
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const PoseReadings& p = poses[i];
    if (p.cycles.size() < 2) continue;
    IsoPose pose;
    pose.name = "P" + std::to_string(i + 1);
    pose.lat_deg = p.first->lat_deg;
    pose.lon_deg = p.first->lon_deg;
    pose.cycles = static_cast<int>(p.cycles.size());
    pose.commanded_mm = commanded(*p.first);
    std::vector<double> errors;
    for (const Sample* s : p.cycles) {
      errors.push_back(s->length_mm - commanded(*s));
      pose.mean_attained_mm += s->length_mm / static_cast<double>(p.cycles.size());
    }
    figures(errors, pose.accuracy, pose.repeatability);
    out.readings += pose.cycles;
    out.poses.push_back(pose);
  }
  if (out.poses.empty())
    throw std::invalid_argument("no pose was measured on two cycles after the " +
                                std::to_string(warmup_cycles) + " warm-up cycles");

  // P1 to each other pose, within a cycle.
  const PoseReadings& p1 = poses.front();
  for (std::size_t i = 1; i < poses.size(); ++i) {
    const std::size_t n = std::min(p1.cycles.size(), poses[i].cycles.size());
    if (n < 2) continue;
    IsoPair pair{"P1", "P" + std::to_string(i + 1), static_cast<int>(n), 0, {}, {}};
    pair.commanded_change_mm = commanded(*poses[i].first) - commanded(*p1.first);
    std::vector<double> errors;
    for (std::size_t k = 0; k < n; ++k) {
      const Sample& a = *p1.cycles[k];
      const Sample& b = *poses[i].cycles[k];
      errors.push_back((b.length_mm - a.length_mm) - (commanded(b) - commanded(a)));
    }
    figures(errors, pair.accuracy, pair.repeatability);
    out.pairs.push_back(pair);
  }

  // P1's drift: its distance regressed on time over the measured cycles (measureDrift, one place).
  std::vector<Sample> p1_samples;
  for (const Sample* s : p1.cycles) p1_samples.push_back(*s);
  Eigen::VectorXd p1_errors(static_cast<Eigen::Index>(p1_samples.size()));
  for (std::size_t k = 0; k < p1_samples.size(); ++k)
    p1_errors[static_cast<Eigen::Index>(k)] = p1_samples[k].length_mm - commanded(p1_samples[k]);
  const Drift d = measureDrift(p1_samples, p1_errors);
  if (d.measured) {
    const double span_h = d.span_min / 60;
    const double change = d.rate_mm_per_h * span_h;
    const double half = studentT975(d.readings - 2) * d.rate_sigma_mm_per_h * span_h;
    out.drift = {true, d.span_min, {change, change - half, change + half}};
  }
  return out;
}

}  // namespace robocal
