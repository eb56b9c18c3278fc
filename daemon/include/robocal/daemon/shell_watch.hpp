// Watches the data points of a run for a connection that goes bad while a shell is measured (a
// ball working loose in its socket, a bar knocked in its chuck). Each point brings its bar
// deflection (the refined model's error there: the points are planned with it) and the noise of
// the readings in its window: their standard deviation, not their range, which grows with their
// number (a window of the main job caught more readings while the machine was busy, and the
// median range of a shell went 2.5x the run's: a pause for nothing). A shell whose recent points
// jump well above what the run has seen so far is suspect: its last kPoints points are compared, as
// medians, with all earlier points. A deflection is judged only past the run's re-centring
// threshold (the soft limit, where a move stops and the ball is moved back along the bar): below it
// a deflection is the model's ordinary error, which the centring corrects as it goes, and a shell
// may start anywhere up to it (a floor of 0.3 mm paused ordinary runs whose shells sat at 0.45 mm).
// A loose ball shows first in the noise of the readings at a point, which is judged from
// kFloorNoiseMm and at kNoiseJump times the earlier points': a loose ball's play of 0.25 mm (1
// sigma) beside a bar's noise of 0.06 mm raised the median spread 3-4x, not the 5x the deflection
// needs (scripts/pause-seeds.sh), while an ordinary shell's median of five stays within 2x of the
// run's. Pure decision, no I/O: the run feeds it and pauses on a problem.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace robocal::daemon {

class ShellWatch {
 public:
  static constexpr std::size_t kPoints = 5;           // recent points judged together
  static constexpr std::size_t kBaselinePoints = 10;  // earlier points needed to judge at all
  static constexpr double kJump = 5.0;       // recent median deflection over the earlier points'
  static constexpr double kNoiseJump = 2.5;  // the same for the noise of the readings
  // Below this the noise is never judged: a loose ball's play is 0.25 mm (1 sigma), and a quiet
  // bar (the tests' cells, 0.02 mm) paused a run under TSan at 0.048 mm, 2.7x its noise (0.03
  // was the floor then). At a real bar's noise (0.06-0.08 mm) 2.5x is above it anyway.
  static constexpr double kFloorNoiseMm = 0.1;

  // `recentre_mm`: the deflection past which the run re-centres the bar (its soft limit).
  explicit ShellWatch(double recentre_mm) : floor_deflection_mm_(recentre_mm) {}

  void startShell() {
    for (double v : shell_deflections_) baseline_deflections_.push_back(v);
    for (double v : shell_noises_) baseline_noises_.push_back(v);
    shell_deflections_.clear();
    shell_noises_.clear();
  }

  // "" while the shell looks like the rest of the run; otherwise what jumped and by how much.
  std::string point(double deflection_mm, double noise_mm) {
    shell_deflections_.push_back(std::abs(deflection_mm));
    shell_noises_.push_back(noise_mm);
    if (shell_deflections_.size() < kPoints || baseline_deflections_.size() < kBaselinePoints)
      return {};
    const auto judge = [](const std::vector<double>& recent_all, const std::vector<double>& base,
                          double floor_mm, double jump, const char* what) -> std::string {
      const std::vector<double> recent(recent_all.end() - kPoints, recent_all.end());
      const double now = median(recent), before = median(base);
      if (now <= std::max(floor_mm, jump * before)) return {};
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the bar %s of the last %zu points is %.3f mm (median), %.3f mm before", what,
                    kPoints, now, before);
      return buf;
    };
    std::string problem =
        judge(shell_noises_, baseline_noises_, kFloorNoiseMm, kNoiseJump, "reading noise");
    if (problem.empty())
      problem = judge(shell_deflections_, baseline_deflections_, floor_deflection_mm_, kJump,
                      "deflection");
    return problem;
  }

 private:
  static double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  double floor_deflection_mm_;
  std::vector<double> baseline_deflections_, baseline_noises_;
  std::vector<double> shell_deflections_, shell_noises_;
};

}  // namespace robocal::daemon
