// The adaptive dwell's two safeguards, without I/O (docs/settling.md):
// - StillNoise: the bar reader's noise measured on this cell, now: the pooled standard deviation
//   of the windows read with the robot still after a full settle_s (the connection check's), so
//   that the adaptive dwell judges "steady" against the noise the bar really has, not a figure
//   typed into a config file.
// - DwellAudit: now and then a point dwells the full settle_s although its readings looked steady
//   earlier; the reading the adaptive dwell would have taken (the window right after it judged
//   steady) is compared with the fixed dwell's. A difference beyond what the noise explains is a
//   bias of the adaptive dwell on this cell (a ring slower than its window, a noise figure set too
//   high): past `kFailuresAllowed` of them the run keeps the fixed dwell.
// Deterministic: the same figures give the same answers.
#pragma once

#include <cstddef>

namespace robocal::daemon {

class StillNoise {
 public:
  // One window of `readings` readings with standard deviation `stddev_mm` about their mean.
  void add(double stddev_mm, std::size_t readings);
  void clear() { *this = StillNoise{}; }
  // Degrees of freedom pooled (readings minus one per window).
  std::size_t dof() const { return dof_; }
  // The pooled standard deviation (0 before any window of two readings or more).
  double mm() const;

 private:
  double squares_ = 0;
  std::size_t dof_ = 0;
};

class DwellAudit {
 public:
  static constexpr double kZ = 4;             // a difference beyond kZ sigma fails the audit
  static constexpr int kFailuresAllowed = 1;  // the adaptive dwell is kept up to this many
  struct Verdict {
    double difference_mm = 0;  // adaptive window's mean - fixed window's mean
    double sigma_mm = 0;       // the difference's standard deviation with no bias
    bool passed = true;
  };
  // One audited point: each window's mean and number of readings (> 0), and the reader's noise.
  Verdict add(double adaptive_mean_mm, std::size_t adaptive_readings, double fixed_mean_mm,
              std::size_t fixed_readings, double noise_mm);
  // The adaptive dwell still trusted (no more failed audits than allowed).
  bool trusted() const { return failures_ <= kFailuresAllowed; }
  int audits() const { return audits_; }
  int failures() const { return failures_; }

 private:
  int audits_ = 0, failures_ = 0;
};

}  // namespace robocal::daemon
