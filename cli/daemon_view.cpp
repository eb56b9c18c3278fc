#include "daemon_view.hpp"

#include <robocal/formats/result_verdict.hpp>

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
std::string connectionWords(const proto::Prompt& p) {
  std::string s = "ball " + std::to_string(p.ball.value_or(0)) + " to chuck " +
                  std::to_string(p.chuck.value_or(0));
  const double ext = p.extension_mm.value_or(0.0);
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

std::string promptText(const proto::Prompt& p) {
  const int shell = p.shell;
  const std::string shell_opt = shell > 0 ? " --shell " + std::to_string(shell) : "";
  std::vector<std::string> lines;
  switch (p.action) {
    case proto::PromptAction::kConnect:
      lines = {"OPERATOR: CONNECT THE BALL-BAR   (shell " + std::to_string(shell) + ")",
               "",
               "Connect " + connectionWords(p) + ".",
               "",
               "Then type:            robocal confirm" + shell_opt,
               "If it will not seat:  robocal nudge --mm D" + shell_opt,
               "                      (D mm along the bar, + away from the chuck)"};
      break;
    case proto::PromptAction::kDetach:
      lines = {shell > 0
                   ? "OPERATOR: DETACH THE BALL-BAR   (before shell " + std::to_string(shell) + ")"
                   : "OPERATOR: THE RUN IS COMPLETE: DETACH THE BALL-BAR",
               ""};
      lines.push_back(p.ball ? "Take the bar off (" + connectionWords(p) + ")."
                             : "Take the bar off the robot.");
      lines.insert(lines.end(), {"Nothing moves until you confirm.", "",
                                 "Then type:  robocal confirm" + shell_opt});
      break;
  }
  return boxed(lines);
}

std::string stateText(const proto::State& e) {
  return stateText(e.to, e.reason);
}

std::string stateText(proto::RunState to_state, const std::string& reason) {
  const std::string to = proto::runStateName(to_state);
  std::string out = "state: " + to;
  if (!reason.empty()) out += " - " + reason;
  out += "\n";
  if (to_state == proto::RunState::kPaused || to_state == proto::RunState::kInterrupted)
    out += "  The robot is stopped. To continue: robocal resume    To end the run: robocal abort\n";
  else if (to_state == proto::RunState::kError)
    out += "  Nothing is moving. Fix the cause above, then: robocal start\n";
  return out;
}

std::string wrapText(const std::string& text, std::size_t width) {
  width = std::max<std::size_t>(width, 20);
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    const bool newline = end != std::string::npos;
    if (!newline) end = text.size();
    std::string line = text.substr(start, end - start);
    std::string indent;
    while (line.size() + indent.size() > width) {
      const std::size_t room = width - indent.size();
      std::size_t cut = line.rfind(' ', room);
      if (cut == std::string::npos || cut == 0) cut = line.find(' ', room);  // one long word
      if (cut == std::string::npos) break;
      out += indent + line.substr(0, cut) + "\n";
      line = line.substr(line.find_first_not_of(' ', cut) == std::string::npos
                             ? line.size()
                             : line.find_first_not_of(' ', cut));
      indent = "  ";
    }
    out += indent + line + (newline ? "\n" : "");
    start = end + 1;
  }
  return out;
}

std::string progressLine(const proto::Progress& p, std::optional<double> bar_mm) {
  const int done = p.points_done, total = p.points_total;
  if (total <= 0)
    return std::string("no run in progress") + (bar_mm ? format("  bar %+.3f mm", *bar_mm) : "");
  constexpr int kWidth = 20;
  const int filled = total > 0 ? std::clamp(kWidth * done / total, 0, kWidth) : 0;
  // Shell 0 is no shell: before the first (its connect prompt) it is the first to come, at the
  // end's detach the last.
  const int shell = p.shell > 0 ? p.shell : done < total ? 1 : p.shells;
  std::string line = "[" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "] " +
                     std::to_string(done) + "/" + std::to_string(total) + "  shell " +
                     std::to_string(shell) + "/" + std::to_string(p.shells);
  if (!p.connection.empty()) line += " " + p.connection;
  line += "  left " + clockText(p.eta_s);
  if (bar_mm) line += "  bar " + format("%+.3f mm", *bar_mm);
  return line;
}

std::string statusText(const proto::Status& s) {
  std::string out = stateText(s.state, s.reason);
  if (!s.run.empty()) {
    out += "run: " + s.run + "\n";
    const bool over = s.state == proto::RunState::kDone || s.state == proto::RunState::kAborted ||
                      s.state == proto::RunState::kIdle;
    if (s.points_total > 0 && !over) out += progressLine(s.progress(), std::nullopt) + "\n";
  }
  const auto device = [](const char* name, bool connected,
                         const std::optional<std::string>& error) {
    std::string line = std::string(name) + (connected ? "connected" : "NOT connected");
    if (error) line += " (" + *error + ")";
    return line + "\n";
  };
  out += device("VAL II controller: ", s.devices.val, s.devices.val_error);
  out += device("ball-bar reader:   ", s.devices.bar, s.devices.bar_error);
  if (s.bar && s.bar->deflection_mm)
    out += "bar: " + format("%+.4f mm deflection", *s.bar->deflection_mm) + "\n";
  if (s.bar_attached)
    out += "the ball-bar may be attached to the robot: the next run asks to detach it first\n";
  if (!s.resumable.empty()) out += "resumable run: " + s.resumable + " (robocal resume)\n";
  out += "clients: " + std::to_string(s.clients) + "\n";
  if (s.prompt) out += promptText(*s.prompt);
  return out;
}

// RESULT: the run's fields are typed; the fit's (as `robocal solve --json`) are read from `fit`.
std::string resultText(const proto::Result& result) {
  if (!result.available)
    return (result.message.empty() ? std::string("no fit yet") : result.message) + "\n";
  const json& r = result.fit;
  std::ostringstream out;
  out << "run " << result.run << ", set " << result.set << " (" << format("%g", result.extension_mm)
      << " mm extension): " << r.value("n", 0) << " samples, rank " << r.value("rank", 0) << " of "
      << r.value("parameters", 54) << "\n";
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
  if (r.contains("outliers") && !r["outliers"].empty())
    out << "  outliers: " << r["outliers"].size() << "\n";
  out << "  report: " << result.report_dir << "/summary.html\n";
  if (r.contains("verdict")) {
    out << resultVerdictText(resultVerdictFromJson(r["verdict"]));
  } else {  // a daemon from before the verdict object
    if (r.contains("problems"))
      for (const json& p : r["problems"])
        out << "  NOT USABLE AS IS: " << (p.is_string() ? p.get<std::string>() : p.dump()) << "\n";
    out << "  calibrated model: " << result.calibrated_file << "\n";
  }
  return out.str();
}

std::string runsText(const proto::Runs& r) {
  if (r.runs.empty()) return "no runs yet\n";
  std::string out = "run                    status       reason\n";
  for (const proto::RunEntry& run : r.runs) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%-22s %-12s ", run.run.c_str(), run.status.c_str());
    out += buf + run.reason + "\n";
  }
  return out;
}

std::string modelsText(const proto::Models& m) {
  if (m.models.empty()) return "no calibrated models yet (each fit of a run stores one)\n";
  std::string out =
      "version  date                  run                  set  samples  fit RMS   work-volume  "
      "checks\n";
  for (const proto::ModelEntry& e : m.models) {
    char buf[256];
    const std::string work =
        e.work_volume_error_mm ? std::to_string(*e.work_volume_error_mm).substr(0, 6) + " mm" : "-";
    const std::string last_check =
        e.checks.empty() ? "none"
                         : std::to_string(e.checks.size()) + ", last " + e.checks.back().verdict;
    std::snprintf(buf, sizeof buf, "%s%6d  %-21s %-20s %3d  %7d  %.4f mm  %-11s  %s%s\n",
                  e.active ? "*" : " ", e.version, e.date_utc.c_str(), e.run.c_str(), e.set,
                  e.samples, e.fit_rms_mm, work.c_str(), last_check.c_str(),
                  e.usable ? "" : "  (not usable)");
    out += buf;
  }
  out += m.active ? "* active: version " + std::to_string(*m.active) + " (compensate uses it)\n"
                  : "no model is active: robocal activate VERSION\n";
  return out;
}

std::string planText(const proto::Plan& p) {
  std::ostringstream out;
  out << "plan (" << p.source << "): " << p.shells << " shells, " << p.points << " points, "
      << p.vias << " vias, " << p.dropped << " dropped; robot time " << clockText(p.duration_s)
      << "\n";
  out << "  rank " << p.rank << ", condition number " << format("%.0f", p.condition_number)
      << ", largest deviation from a shell " << format("%.2f", p.max_deviation_mm) << " mm\n";
  if (p.predicted_work_volume_error_mm >= 0) {
    out << "  predicted error after the fit: " << format("%.3f", p.predicted_work_volume_error_mm)
        << " mm RMS in the work volume";
    if (p.predicted_whole_range_error_mm >= 0)
      out << ", " << format("%.3f", p.predicted_whole_range_error_mm)
          << " mm over the arm's whole range";
    out << "\n";
  }
  if (p.predicted_change_mm >= 0)
    out << "  forecast: the bar deflects up to " << format("%.2f", p.predicted_deflection_mm)
        << " mm, changes by up to " << format("%.2f", p.predicted_change_mm)
        << " mm from its reading at the connect pose\n";
  return out.str();
}

}  // namespace robocal::cli
