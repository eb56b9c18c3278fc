#include <robocal/daemon/dwell_audit.hpp>

#include <algorithm>
#include <cmath>

namespace robocal::daemon {

void StillNoise::add(double stddev_mm, std::size_t readings) {
  if (readings < 2) return;
  squares_ += stddev_mm * stddev_mm * static_cast<double>(readings - 1);
  dof_ += readings - 1;
}

double StillNoise::mm() const {
  return dof_ == 0 ? 0 : std::sqrt(squares_ / static_cast<double>(dof_));
}

DwellAudit::Verdict DwellAudit::add(double adaptive_mean_mm, std::size_t adaptive_readings,
                                    double fixed_mean_mm, std::size_t fixed_readings,
                                    double noise_mm) {
  Verdict v;
  v.difference_mm = adaptive_mean_mm - fixed_mean_mm;
  const auto inverse = [](std::size_t n) {
    return 1.0 / static_cast<double>(std::max<std::size_t>(n, 1));
  };
  v.sigma_mm = noise_mm * std::sqrt(inverse(adaptive_readings) + inverse(fixed_readings));
  v.passed = std::abs(v.difference_mm) <= kZ * v.sigma_mm;
  ++audits_;
  if (!v.passed) ++failures_;
  return v;
}

}  // namespace robocal::daemon
