#include <robocal/daemon/steady_window.hpp>

#include <algorithm>
#include <cmath>

namespace robocal::daemon {

bool SteadyWindow::add(double t_s, double value_mm) {
  points_.push_back({t_s, value_mm});
  while (!points_.empty() && points_.front().t_s < t_s - c_.window_s) points_.pop_front();
  steady_ = false;
  const std::size_t n = points_.size();
  if (n < std::max<std::size_t>(c_.min_readings, 3) ||
      points_.back().t_s - points_.front().t_s < 0.9 * c_.window_s)
    return false;
  // Least-squares line through the window, about its mean time (well conditioned).
  double t_mean = 0, v_mean = 0;
  for (const Point& p : points_) {
    t_mean += p.t_s;
    v_mean += p.value_mm;
  }
  t_mean /= static_cast<double>(n);
  v_mean /= static_cast<double>(n);
  double stt = 0, stv = 0;
  for (const Point& p : points_) {
    stt += (p.t_s - t_mean) * (p.t_s - t_mean);
    stv += (p.t_s - t_mean) * (p.value_mm - v_mean);
  }
  if (stt <= 0) return false;
  const double slope = stv / stt;
  double ss = 0;
  for (const Point& p : points_) {
    const double r = p.value_mm - (v_mean + slope * (p.t_s - t_mean));
    ss += r * r;
  }
  trend_mm_ = slope * c_.window_s;
  spread_mm_ = std::sqrt(ss / static_cast<double>(n - 2));
  steady_ = std::abs(trend_mm_) <= c_.trend_factor * c_.noise_mm &&
            spread_mm_ <= c_.spread_factor * c_.noise_mm;
  return steady_;
}

}  // namespace robocal::daemon
