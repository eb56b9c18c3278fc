#include <robocal/compensation/accuracy_report.hpp>

#include <robocal/formats/axis_ticks.hpp>
#include <robocal/formats/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

namespace robocal {
namespace {

using ojson = nlohmann::ordered_json;

ojson statsJson(const ErrorStats& s) {
  return {{"rms", s.rms}, {"p95", s.p95}, {"max", s.max}};
}

std::string fmt(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c, d);
  return buf;
}

std::string statsLine(const char* what, const ErrorStats& s, const char* unit, int decimals) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "  %-44s RMS %.*f %s, p95 %.*f %s, max %.*f %s\n", what, decimals,
                s.rms, unit, decimals, s.p95, unit, decimals, s.max, unit);
  return buf;
}

// A round step (1, 2 or 5 times a power of ten) that cuts `span` into about `parts`.
// Viridis-like ramp from dark blue (0) through green to yellow (1).
std::string colour(double t) {
  t = std::clamp(t, 0.0, 1.0);
  const double stops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  const double x = t * 4;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  char buf[16];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x",
                static_cast<int>(stops[i][0] + f * (stops[i + 1][0] - stops[i][0])),
                static_cast<int>(stops[i][1] + f * (stops[i + 1][1] - stops[i][1])),
                static_cast<int>(stops[i][2] + f * (stops[i + 1][2] - stops[i][2])));
  return buf;
}

struct Panel {
  std::string title;
  std::function<double(const PoseAccuracy&)> value;  // mm
  // Panels of one group share their colour scale: the calibrated errors, predicted and true, are
  // read against each other; the nominal's, 50-100x larger, has its own.
  int scale_group = 0;
};

}  // namespace

ojson accuracyJson(const AccuracyReport& r, bool per_pose) {
  ojson out = {
      {"poses_from", r.poses_from}, {"poses", r.requested}, {"ok", r.ok}, {"solved", r.solved}};
  if (r.predicted_position_mm.count) {
    out["predicted_position_error_mm"] = statsJson(r.predicted_position_mm);
    out["predicted_orientation_error_deg"] = statsJson(r.predicted_orientation_deg);
  }
  if (r.has_truth) {
    out["nominal_commanded_position_error_mm"] = statsJson(r.nominal_position_mm);
    out["nominal_commanded_orientation_error_deg"] = statsJson(r.nominal_orientation_deg);
    out["compensated_commanded_position_error_mm"] = statsJson(r.compensated_position_mm);
    out["compensated_commanded_orientation_error_deg"] = statsJson(r.compensated_orientation_deg);
    out["calibrated_model_position_error_mm"] = statsJson(r.calibrated_model_position_mm);
    out["calibrated_model_orientation_error_deg"] = statsJson(r.calibrated_model_orientation_deg);
  }
  if (per_pose) {
    ojson poses = ojson::array();
    for (const PoseAccuracy& p : r.poses) {
      const CompensatedTarget& t = p.target;
      const LinkParams pose = linkFromTransform(t.target);
      ojson one = {
          {"pose", {pose.x_mm, pose.y_mm, pose.z_mm, pose.rz_deg, pose.ry_deg, pose.rx_deg}},
          {"status", compensationStatusName(t.status)},
          {"note", t.reason},
          {"config", armConfigName(t.config)},
          {"nominal_joints_deg",
           std::vector<double>(t.nominal_joints_deg.data(), t.nominal_joints_deg.data() + 6)},
          {"joints_deg", std::vector<double>(t.joints_deg.data(), t.joints_deg.data() + 6)},
          // each joint's direction into the target (1: up from its pre-point); null: none
          {"approach", t.hasApproach() ? ojson(t.approach) : ojson(nullptr)}};
      if (!std::isnan(t.predicted_position_error_mm)) {
        one["predicted_position_error_mm"] = t.predicted_position_error_mm;
        one["predicted_orientation_error_deg"] = t.predicted_orientation_error_deg;
      }
      if (r.has_truth) {
        one["nominal_commanded_position_error_mm"] = p.nominal_commanded.position_mm;
        one["compensated_commanded_position_error_mm"] = p.compensated_commanded.position_mm;
      }
      poses.push_back(one);
    }
    out["per_pose"] = poses;
  }
  return out;
}

std::string accuracyText(const AccuracyReport& r) {
  std::string out = "accuracy over " + std::to_string(r.solved) + " of " +
                    std::to_string(r.requested) + " target poses (" + r.poses_from + ")";
  out += r.solved < r.requested ? "; the others could not be compensated\n" : "\n";
  if (r.ok < r.solved)
    out += "  " + std::to_string(r.solved - r.ok) +
           " of them lie where the calibration says little (outside the joint ranges it "
           "measured, or a predicted error above the correction): see the per-pose status\n";
  if (r.predicted_position_mm.count) {
    out += statsLine("predicted 1-sigma error, position:", r.predicted_position_mm, "mm", 4);
    out +=
        statsLine("predicted 1-sigma error, orientation:", r.predicted_orientation_deg, "deg", 5);
  } else {
    out += "  predicted error: the calibrated model has no covariance (fit it with this robocal)\n";
  }
  if (r.has_truth) {
    out += "against the truth:\n";
    out += statsLine("commanded with nominal joints, position:", r.nominal_position_mm, "mm", 4);
    out += statsLine("commanded with compensated joints, position:", r.compensated_position_mm,
                     "mm", 4);
    out += statsLine("calibrated model's own error, position:", r.calibrated_model_position_mm,
                     "mm", 4);
    out += statsLine("commanded with nominal joints, orientation:", r.nominal_orientation_deg,
                     "deg", 5);
    out += statsLine(
        "commanded with compensated joints, orientation:", r.compensated_orientation_deg, "deg", 5);
    const double nominal = r.nominal_position_mm.rms, compensated = r.compensated_position_mm.rms;
    if (nominal > 0 && compensated > 0 && nominal >= compensated)
      out +=
          fmt("  compensation makes the RMS position error %.1fx smaller\n", nominal / compensated);
    else if (nominal > 0 && compensated > 0)
      out +=
          fmt("  compensation makes the RMS position error %.1fx LARGER here: the calibration does "
              "not cover these poses\n",
              compensated / nominal);
  }
  return out;
}

std::string accuracySvg(const AccuracyReport& r) {
  std::vector<Panel> panels;
  if (r.predicted_position_mm.count)
    panels.push_back({"predicted 1-sigma position error",
                      [](const PoseAccuracy& p) { return p.target.predicted_position_error_mm; }});
  if (r.has_truth) {
    panels.push_back({"true error, nominal joints",
                      [](const PoseAccuracy& p) { return p.nominal_commanded.position_mm; }, 1});
    panels.push_back({"true error, compensated joints",
                      [](const PoseAccuracy& p) { return p.compensated_commanded.position_mm; }});
  }
  std::vector<const PoseAccuracy*> ok;
  for (const PoseAccuracy& p : r.poses)
    if (p.target.solved()) ok.push_back(&p);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const PoseAccuracy* p : ok) {
    const Eigen::Vector3d t = p->target.target.translation();
    x0 = std::min(x0, t.x()), x1 = std::max(x1, t.x());
    y0 = std::min(y0, t.y()), y1 = std::max(y1, t.y());
  }
  if (ok.empty()) x0 = y0 = 0, x1 = y1 = 1;
  // One step on both axes: the map keeps its aspect.
  const double axis_step = niceTicks(0, std::max(x1 - x0, y1 - y0), 5).step;
  x0 = std::floor(x0 / axis_step) * axis_step, x1 = std::ceil(x1 / axis_step) * axis_step;
  y0 = std::floor(y0 / axis_step) * axis_step, y1 = std::ceil(y1 / axis_step) * axis_step;
  const double plot = 300, left = 60, top = 70, gap = 150;
  const double scale = plot / std::max(x1 - x0, y1 - y0);
  const double width = left + panels.size() * (plot + gap), height = top + plot + 60;
  std::string svg =
      fmt("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
          "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" "
          "fill=\"white\"/>\n",
          std::max(width, 480.0), height);  // the title fits
  svg +=
      "<text x=\"10\" y=\"20\" font-size=\"14\">Tool position error over the work volume, "
      "seen from above</text>\n<text x=\"10\" y=\"38\">" +
      std::to_string(ok.size()) + " poses; world frame = chuck fixture</text>\n";
  for (size_t k = 0; k < panels.size(); ++k) {
    const double ox = left + k * (plot + gap);
    double vmax = 0;
    for (const Panel& panel : panels)
      if (panel.scale_group == panels[k].scale_group)
        for (const PoseAccuracy* p : ok) vmax = std::max(vmax, panel.value(*p));
    const AxisTicks colour_ticks = niceTicks(0, vmax > 0 ? vmax : 1e-3, 4);
    const double cmax = colour_ticks.last();
    svg += fmt("<text x=\"%.0f\" y=\"%.0f\" font-size=\"13\">", ox, top - 10) + panels[k].title +
           "</text>\n";
    svg +=
        fmt("<rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" "
            "stroke=\"#888\"/>\n",
            ox, top, plot, plot);
    for (double v = x0; v <= x1 + 1e-9; v += axis_step) {
      const double px = ox + (v - x0) * scale;
      svg += fmt("<line x1=\"%.1f\" y1=\"%.0f\" x2=\"%.1f\" y2=\"%.0f\" stroke=\"#eee\"/>\n", px,
                 top, px, top + plot);
      svg += fmt("<text x=\"%.1f\" y=\"%.0f\" text-anchor=\"middle\">%g</text>\n", px,
                 top + plot + 15, v);
    }
    for (double v = y0; v <= y1 + 1e-9; v += axis_step) {
      const double py = top + plot - (v - y0) * scale;
      svg += fmt("<line x1=\"%.0f\" y1=\"%.1f\" x2=\"%.0f\" y2=\"%.1f\" stroke=\"#eee\"/>\n", ox,
                 py, ox + plot, py);
      svg += fmt("<text x=\"%.0f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", ox - 5, py + 4, v);
    }
    svg += fmt("<text x=\"%.0f\" y=\"%.0f\" text-anchor=\"middle\">x (mm)</text>\n", ox + plot / 2,
               top + plot + 32);
    svg += fmt("<text x=\"%.0f\" y=\"%.0f\" text-anchor=\"middle\" ", ox - 42, top + plot / 2) +
           fmt("transform=\"rotate(-90 %.0f %.0f)\">y (mm)</text>\n", ox - 42, top + plot / 2);
    for (const PoseAccuracy* p : ok) {
      const Eigen::Vector3d t = p->target.target.translation();
      svg += fmt("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" ", ox + (t.x() - x0) * scale,
                 top + plot - (t.y() - y0) * scale) +
             "fill=\"" + colour(panels[k].value(*p) / cmax) + "\"/>\n";
    }
    // The colour bar, with round ticks in mm.
    const double bx = ox + plot + 15;
    for (int i = 0; i < 50; ++i)
      svg += fmt("<rect x=\"%.0f\" y=\"%.1f\" width=\"14\" height=\"%.1f\" ", bx,
                 top + plot - (i + 1) * plot / 50, plot / 50 + 0.5) +
             "fill=\"" + colour((i + 0.5) / 50) + "\"/>\n";
    for (double v : colour_ticks.values())
      svg += fmt("<text x=\"%.0f\" y=\"%.1f\">", bx + 18, top + plot - v / cmax * plot + 4) +
             colour_ticks.label(v) + "</text>\n";
    svg += fmt("<text x=\"%.0f\" y=\"%.0f\">mm</text>\n", bx, top + plot + 15);
  }
  svg += "</svg>\n";
  return svg;
}

AccuracyReport predictedWorkVolumeAccuracy(const Compensator& compensator, const WorkVolume& work,
                                           const std::string& poses_from) {
  AccuracyReport report = assessAccuracy(compensator, workVolumePoses(work, compensator));
  report.poses_from = poses_from;
  return report;
}

AccuracyReport predictedWholeRangeAccuracy(const Compensator& compensator) {
  const std::vector<JointsDeg> joints = wholeRangeJoints(compensator.calibratedArm());
  AccuracyReport report = assessAccuracyAtJoints(compensator, joints);
  report.poses_from = "the arm's whole range: " + std::to_string(joints.size()) +
                      " joint vectors within its limits";
  return report;
}

PredictedAccuracy predictedAccuracy(const Model& nominal, const Model& calibrated,
                                    const WorkVolume& work) {
  PredictedAccuracy out;
  try {
    const Compensator compensator(nominal, calibrated);
    try {
      AccuracyReport volume =
          predictedWorkVolumeAccuracy(compensator, work, "the cell's work_volume");
      out.work_volume = accuracyJson(volume);
      out.text = accuracyText(volume);
      out.work_volume_rms_mm = volume.predicted_position_mm.rms;
      out.work_volume_report = std::move(volume);
    } catch (const std::exception& e) {  // the volume is out of reach
      out.work_volume = {{"error", e.what()}};
      out.text = std::string("work-volume accuracy: ") + e.what() + "\n";
      out.problem = std::string("work volume: ") + e.what();
    }
    const AccuracyReport whole = predictedWholeRangeAccuracy(compensator);
    out.whole_range = accuracyJson(whole);
    out.text += accuracyText(whole);
    out.whole_range_rms_mm = whole.predicted_position_mm.rms;
  } catch (const std::exception& e) {  // a model compensation cannot use
    out.work_volume = out.whole_range = {{"error", e.what()}};
    out.text = std::string("accuracy: ") + e.what() + "\n";
    out.problem = e.what();
  }
  return out;
}

std::string writeWorkVolumeReport(const std::string& dir, const AccuracyReport& report) {
  writeTextFileAtomic(dir + "/work_volume.json", accuracyJson(report, true).dump(2) + "\n");
  std::string svg = accuracySvg(report);
  writeTextFileAtomic(dir + "/work_volume.svg", svg);
  return svg;
}

}  // namespace robocal
