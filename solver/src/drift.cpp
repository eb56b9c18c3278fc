#include <robocal/solver/adequacy.hpp>
#include <robocal/solver/drift.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

namespace robocal {

Drift measureDrift(const std::vector<Sample>& samples, const Eigen::VectorXd& residuals,
                   double false_alarm, double limit_mm) {
  Drift d;
  d.limit_mm = limit_mm;
  // (time in hours, residual) of each place.
  std::map<SamplePlace, std::vector<std::pair<double, double>>> places;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    if (!s.time_s) continue;
    places[placeOf(s)].push_back({*s.time_s / 3600, residuals[static_cast<Eigen::Index>(i)]});
  }
  // Sums about each place's means: a slope common to all places, an offset for each.
  double stt = 0, str = 0, srr = 0;
  for (const auto& [place, v] : places) {
    if (v.size() < 2) continue;
    double t_mean = 0, r_mean = 0, t_lo = v[0].first, t_hi = v[0].first;
    for (const auto& [t, r] : v) {
      t_mean += t;
      r_mean += r;
      t_lo = std::min(t_lo, t);
      t_hi = std::max(t_hi, t);
    }
    t_mean /= static_cast<double>(v.size());
    r_mean /= static_cast<double>(v.size());
    for (const auto& [t, r] : v) {
      stt += (t - t_mean) * (t - t_mean);
      str += (t - t_mean) * (r - r_mean);
      srr += (r - r_mean) * (r - r_mean);
    }
    ++d.places;
    d.readings += static_cast<int>(v.size());
    d.span_min = std::max(d.span_min, 60 * (t_hi - t_lo));
  }
  const int dof = d.readings - d.places - 1;  // an offset per place and the slope
  if (stt <= 0 || dof < 1) return d;
  d.measured = true;
  d.rate_mm_per_h = str / stt;
  const double scatter = std::max(0.0, srr - d.rate_mm_per_h * str) / dof;
  d.rate_sigma_mm_per_h = std::sqrt(scatter / stt);
  d.over_span_mm = std::abs(d.rate_mm_per_h) * d.span_min / 60;
  const double z2 = d.rate_sigma_mm_per_h > 0 ? std::pow(d.rate_mm_per_h / d.rate_sigma_mm_per_h, 2)
                                              : (d.rate_mm_per_h != 0 ? INFINITY : 0.0);
  d.significant = z2 > chi2Quantile(1, false_alarm);
  d.found = d.significant && d.over_span_mm > d.limit_mm;
  return d;
}

std::string Drift::summary() const {
  char buf[300];
  if (!measured) {
    std::snprintf(buf, sizeof buf,
                  "drift not measured (%d places measured twice with times; a reference pose: "
                  "motion.reference_every_min)",
                  places);
  } else if (found) {
    std::snprintf(buf, sizeof buf,
                  "drift found: the reading changes %+.4f mm/h (+/- %.4f, 1 sigma, %d places), "
                  "%.4f mm over the %.0f min a place was measured, more than the %.3f mm allowed",
                  rate_mm_per_h, rate_sigma_mm_per_h, places, over_span_mm, span_min, limit_mm);
  } else if (significant) {
    std::snprintf(buf, sizeof buf,
                  "a drift within the %.3f mm allowed: %+.4f mm/h (+/- %.4f, 1 sigma, %d places), "
                  "%.4f mm over the %.0f min a place was measured",
                  limit_mm, rate_mm_per_h, rate_sigma_mm_per_h, places, over_span_mm, span_min);
  } else {
    std::snprintf(buf, sizeof buf,
                  "no drift told from the bar's noise: %+.4f mm/h (+/- %.4f, 1 sigma, %d places) "
                  "over the %.0f min a place was measured",
                  rate_mm_per_h, rate_sigma_mm_per_h, places, span_min);
  }
  return buf;
}

}  // namespace robocal
