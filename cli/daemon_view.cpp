#include "daemon_view.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <vector>

namespace robocal::cli {
namespace {

using json = nlohmann::json;

std::string format(const char* fmt, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, a);
  return buf;
}

// "ball 1 to chuck 3 with the 150 mm extension" / "... without extension".
std::string connectionWords(const json& p) {
  std::string s = "ball " + std::to_string(p.value("ball", 0)) + " to chuck " +
                  std::to_string(p.value("chuck", 0));
  const double ext = p.value("extension_mm", 0.0);
  return s + (ext > 0 ? " with the " + format("%g", ext) + " mm extension" : " without extension");
}

std::string boxed(const std::vector<std::string>& lines) {
  std::size_t width = 0;
  for (const auto& l : lines) width = std::max(width, l.size());
  const std::string rule = "  +" + std::string(width + 4, '-') + "+\n";
  std::string out = "\n" + rule;
  for (const auto& l : lines) out += "  |  " + l + std::string(width - l.size(), ' ') + "  |\n";
  return out + rule;
}

}  // namespace

std::string clockText(double seconds) {
  char buf[32];
  const long t = static_cast<long>(std::max(0.0, seconds) + 0.5);
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return buf;
}

std::string promptText(const json& p) {
  const int shell = p.value("shell", 0);
  const std::string action = p.value("action", "");
  const std::string shell_opt = shell > 0 ? " --shell " + std::to_string(shell) : "";
  std::vector<std::string> lines;
  if (action == "connect") {
    lines = {"OPERATOR: CONNECT THE BALL-BAR   (shell " + std::to_string(shell) + ")",
             "",
             "Connect " + connectionWords(p) + ".",
             "",
             "Then type:            robocal confirm" + shell_opt,
             "If it will not seat:  robocal nudge --mm D" + shell_opt,
             "                      (D mm along the bar, + away from the chuck)"};
  } else if (action == "detach") {
    lines = {shell > 0
                 ? "OPERATOR: DETACH THE BALL-BAR   (before shell " + std::to_string(shell) + ")"
                 : "OPERATOR: THE RUN IS COMPLETE: DETACH THE BALL-BAR",
             ""};
    lines.push_back(p.contains("ball") ? "Take the bar off (" + connectionWords(p) + ")."
                                       : "Take the bar off the robot.");
    lines.insert(lines.end(), {"Nothing moves until you confirm.", "",
                               "Then type:  robocal confirm" + shell_opt});
  } else {
    lines = {"OPERATOR: " + p.value("message", "?"), "", "Then type:  robocal confirm" + shell_opt};
  }
  return boxed(lines);
}

std::string stateText(const json& e) {
  const std::string to = e.value("to", "?");
  std::string out = "state: " + to;
  if (!e.value("reason", "").empty()) out += " - " + e.value("reason", "");
  out += "\n";
  if (to == "paused" || to == "interrupted")
    out += "  The robot is stopped. To continue: robocal resume    To end the run: robocal abort\n";
  else if (to == "error")
    out += "  Nothing is moving. Fix the cause above, then: robocal start\n";
  return out;
}

std::string progressLine(const json& p, std::optional<double> bar_mm) {
  const int done = p.value("points_done", 0), total = p.value("points_total", 0);
  constexpr int kWidth = 20;
  const int filled = total > 0 ? std::clamp(kWidth * done / total, 0, kWidth) : 0;
  std::string line = "[" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "] " +
                     std::to_string(done) + "/" + std::to_string(total) + "  shell " +
                     std::to_string(p.value("shell", 0)) + "/" +
                     std::to_string(p.value("shells", 0));
  if (!p.value("connection", "").empty()) line += " " + p.value("connection", "");
  line += "  left " + clockText(p.value("eta_s", 0.0));
  if (bar_mm) line += "  bar " + format("%+.3f mm", *bar_mm);
  return line;
}

std::string statusText(const json& s) {
  std::string out = stateText({{"to", s.value("state", "?")}, {"reason", s.value("reason", "")}});
  if (!s.value("run", "").empty()) {
    out += "run: " + s.value("run", "") + "\n";
    const std::string state = s.value("state", "");
    const bool over = state == "done" || state == "aborted" || state == "idle";
    if (s.value("points_total", 0) > 0 && !over) out += progressLine(s, std::nullopt) + "\n";
  }
  if (s.contains("devices")) {
    const json& d = s["devices"];
    const auto device = [&](const char* name, const char* key, const char* error_key) {
      std::string line = std::string(name) + (d.value(key, false) ? "connected" : "NOT connected");
      if (d.contains(error_key)) line += " (" + d.value(error_key, "") + ")";
      return line + "\n";
    };
    out += device("VAL II controller: ", "val", "val_error");
    out += device("ball-bar reader:   ", "bar", "bar_error");
  }
  if (s.contains("bar") && s["bar"].contains("deflection_mm"))
    out += "bar: " + format("%+.4f mm deflection", s["bar"]["deflection_mm"].get<double>()) + "\n";
  if (s.value("bar_attached", false))
    out += "the ball-bar may be attached to the robot: the next run asks to detach it first\n";
  if (!s.value("resumable", "").empty())
    out += "resumable run: " + s.value("resumable", "") + " (robocal resume)\n";
  if (s.contains("clients")) out += "clients: " + s["clients"].dump() + "\n";
  if (s.contains("prompt") && s["prompt"].is_object()) out += promptText(s["prompt"]);
  return out;
}

std::string resultText(const json& r) {
  if (!r.value("available", true)) return r.value("message", "no fit yet") + "\n";
  std::ostringstream out;
  out << "run " << r.value("run", "?") << ", set " << r.value("set", 0) << " ("
      << format("%g", r.value("extension_mm", 0.0)) << " mm extension): " << r.value("n", 0)
      << " samples, rank " << r.value("rank", 0) << " of " << r.value("parameters", 54) << "\n";
  out << "  fit RMS " << format("%.4f", r.value("rms_mm", 0.0)) << " mm (nominal model "
      << format("%.4f", r.value("rms_before_mm", 0.0)) << " mm), max "
      << format("%.4f", r.value("max_abs_residual_mm", 0.0)) << " mm\n";
  if (r.contains("validation_rms_mm"))
    out << "  this set predicted by the earlier fit: RMS "
        << format("%.4f", r["validation_rms_mm"].get<double>()) << " mm\n";
  if (r.contains("predicted_ball_error_rms_mm"))
    out << "  predicted ball position error: RMS "
        << format("%.4f", r["predicted_ball_error_rms_mm"].get<double>()) << " mm\n";
  if (r.contains("worst_shells") && !r["worst_shells"].empty()) {
    out << "  worst shells by RMS:";
    for (const json& shell : r["worst_shells"]) out << " " << shell.dump();
    out << " (robocal solve prints the table)\n";
  }
  if (r.contains("problems"))
    for (const json& p : r["problems"])
      out << "  NOT USABLE AS IS: " << (p.is_string() ? p.get<std::string>() : p.dump()) << "\n";
  if (r.contains("outliers") && !r["outliers"].empty())
    out << "  outliers: " << r["outliers"].size() << "\n";
  out << "  calibrated model: " << r.value("calibrated_file", "?") << "\n";
  out << "  report: " << r.value("report_dir", "?") << "\n";
  return out.str();
}

std::string runsText(const json& r) {
  if (!r.contains("runs") || r["runs"].empty()) return "no runs yet\n";
  std::string out = "run                    status       reason\n";
  for (const json& run : r["runs"]) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%-22s %-12s ", run.value("run", "?").c_str(),
                  run.value("status", "?").c_str());
    out += buf + run.value("reason", "") + "\n";
  }
  return out;
}

std::string planText(const json& p) {
  std::ostringstream out;
  out << "plan (" << p.value("source", "?") << "): " << p.value("shells", 0) << " shells, "
      << p.value("points", 0) << " points, " << p.value("vias", 0) << " vias, "
      << p.value("dropped", 0) << " dropped; robot time " << clockText(p.value("duration_s", 0.0))
      << "\n";
  if (p.contains("rank"))
    out << "  rank " << p.value("rank", 0) << ", condition number "
        << format("%.0f", p.value("condition_number", 0.0)) << ", largest deviation from a shell "
        << format("%.2f", p.value("max_deviation_mm", 0.0)) << " mm\n";
  return out.str();
}

}  // namespace robocal::cli
