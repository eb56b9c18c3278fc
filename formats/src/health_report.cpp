#include <robocal/formats/health_report.hpp>

#include "report_parts.hpp"

#include <cctype>
#include <cstdio>

namespace robocal {
namespace {

using nlohmann::ordered_json;

std::string fmt(const char* format, double a = 0, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// "B1C2 +75 mm", as the fit's tables write a shell.
std::string shellText(const ShellResiduals& s) {
  return connectionName(s.connection) +
         (s.extension_mm > 0 ? fmt(" +%.0f mm", s.extension_mm) : std::string());
}

std::string extensionsText(const std::vector<double>& extensions) {
  std::string out;
  for (size_t i = 0; i < extensions.size(); ++i) out += (i ? ", " : "") + fmt("%g", extensions[i]);
  return out + " mm";
}

const char* referenceText(HealthReference reference) {
  switch (reference) {
    case HealthReference::kBaseline:
      return "baseline: the check right after the calibration";
    case HealthReference::kCalibration:
      return "calibration: the active model's fit RMS";
    case HealthReference::kFallback:
      return "fallback: the active model has no provenance RMS";
  }
  return "?";
}

// The value with the precision of the parameter's kind: 4 decimals in mm and deg, 6 for a gain.
std::string value(const ParameterChange& c, double v, bool sign) {
  const bool gain = c.unit == "gain";
  return fmt(gain ? (sign ? "%+.6f" : "%.6f") : (sign ? "%+.4f" : "%.4f"), v);
}

}  // namespace

int healthExitStatus(HealthStatus status) {
  switch (status) {
    case HealthStatus::kPass:
      return kHealthExitPass;
    case HealthStatus::kWarn:
      return kHealthExitWarn;
    case HealthStatus::kFail:
      return kHealthExitFail;
  }
  return kHealthExitFail;
}

std::string healthVerdictText(const HealthVerdict& v) {
  std::string out = "health check: " + upper(healthStatusName(v.status)) + "\n  " + v.reason + "\n";
  out += fmt("samples: %.0f on ", static_cast<double>(v.samples)) + connectionList(v.connections) +
         ", extension " + extensionsText(v.extensions_mm) + "\n";
  out += fmt(
      "residuals under the active model (no refit): RMS %.4f mm, mean %+.4f mm, max |r| %.4f mm\n",
      v.residuals.rms_mm, v.residuals.mean_mm, v.residuals.max_abs_mm);
  out += fmt("reference: %.4f mm (", v.reference_rms_mm) + referenceText(v.reference) + ")\n";
  out +=
      fmt("ratio: %.2f (an unchanged robot's scatters by +/-%.2f); warn from %.2f, fail from "
          "%.2f\n",
          v.rms_ratio, v.ratio_scatter, v.warn_ratio, v.fail_ratio);
  out +=
      fmt("changes judged at a noise of %.4f mm (the check's own level %.4f mm, after what "
          "it names)\n",
          v.noise_mm, v.check_level_mm);
  if (!v.model_covariance)
    out +=
        "note: the model carries no covariance, so its own error at the check's poses is tested "
        "as if it were a change (about 4% false alarms); a model robocal solve or robocald wrote "
        "carries one\n";
  out += "residual per shell:\n";
  out += "  shell  connection        n   RMS (mm)   max (mm)  mean (mm)  RMS/median\n";
  for (const ShellResiduals& s : v.shells.shells) {
    char line[160];
    std::snprintf(line, sizeof line, "  %5d  %-14s %4zu   %8.4f   %8.4f   %+8.4f      %6.2f%s\n",
                  s.shell, shellText(s).c_str(), s.stats.count, s.stats.rms_mm, s.stats.max_abs_mm,
                  s.stats.mean_mm, s.rms_to_median, s.stands_out ? "  !" : "");
    out += line;
  }
  for (const ShellResiduals& s : v.shells.shells)
    if (s.stands_out) {
      out +=
          fmt("  ! an RMS at least %gx the median shell's: check that shell's set-up (a loose "
              "chuck, a mis-seated ball)\n",
              kShellStandsOut);
      break;
    }
  if (v.moved.empty()) {
    out +=
        "what moved: nothing the check can name (no single parameter explains a significant "
        "part of the residuals)\n";
    return out;
  }
  out += "what moved (the named parameters refitted from the active model, with a prior):\n";
  for (const ParameterChange& c : v.moved) {
    out += "  " + c.text + "  (+/-" + value(c, c.sigma, false) + (c.unit == "gain" ? "" : " ") +
           (c.unit == "gain" ? "" : c.unit) +
           fmt(", %.1f sigma; %.1f times its prior sigma)", c.significance, c.prior_ratio);
    if (!c.equivalent.empty()) {
      out += "; the same on these data as";
      for (size_t k = 0; k < c.equivalent.size(); ++k) out += (k ? ", " : " ") + c.equivalent[k];
    }
    out += "\n";
  }
  out += fmt("RMS after refitting them: %.4f mm (%.2f times the reference)\n", v.refit_rms_mm,
             v.refit_ratio);
  return out;
}

ordered_json healthVerdictJson(const HealthVerdict& v) {
  ordered_json out;
  out["status"] = healthStatusName(v.status);
  out["reason"] = v.reason;
  out["samples"] = v.samples;
  ordered_json connections = ordered_json::array();
  for (const Connection& c : v.connections) connections.push_back(connectionName(c));
  out["connections"] = connections;
  out["extensions_mm"] = v.extensions_mm;
  out["rms_mm"] = v.residuals.rms_mm;
  out["mean_mm"] = v.residuals.mean_mm;
  out["max_abs_mm"] = v.residuals.max_abs_mm;
  out["reference_rms_mm"] = v.reference_rms_mm;
  out["reference"] = healthReferenceName(v.reference);
  out["rms_ratio"] = v.rms_ratio;
  out["ratio_scatter"] = v.ratio_scatter;
  out["warn_ratio"] = v.warn_ratio;
  out["fail_ratio"] = v.fail_ratio;
  out["noise_mm"] = v.noise_mm;
  out["check_level_mm"] = v.check_level_mm;
  out["model_covariance"] = v.model_covariance;
  ordered_json moved = ordered_json::array();
  for (const ParameterChange& c : v.moved) {
    ordered_json m;
    m["name"] = c.name;
    m["unit"] = c.unit;
    m["change_" + c.unit] = c.change;
    m["sigma_" + c.unit] = c.sigma;
    m["prior_sigma_" + c.unit] = c.prior_sigma;
    m["significance"] = c.significance;
    m["prior_ratio"] = c.prior_ratio;
    m["text"] = c.text;
    m["equivalent"] = c.equivalent;
    moved.push_back(m);
  }
  out["moved"] = moved;
  out["refit_rms_mm"] = v.refit_rms_mm;
  out["refit_ratio"] = v.refit_ratio;
  ordered_json worst = ordered_json::array();
  for (int k : v.shells.worst) worst.push_back(v.shells.shells[k].shell);
  out["worst_shells"] = worst;
  out["shells"] = report_detail::shellsJson(v.shells);
  return out;
}

}  // namespace robocal
