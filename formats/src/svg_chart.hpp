// Inside formats: a minimal SVG chart for the report's figures. A 900 x 500 page with the plot
// area on the left and a legend column on the right; axes with round ticks (axis_ticks.hpp), a
// light grid at the ticks, and the unit in each axis label. Everything is drawn in data
// coordinates. Not installed.
#pragma once

#include <robocal/formats/axis_ticks.hpp>

#include <string>
#include <utility>
#include <vector>

namespace robocal::report_detail {

// One axis: its label with the unit ("residual (mm)"), the data range to cover, and how to tick
// it. Not numeric: no tick labels, the caller labels positions (SvgChart::xLabel).
struct ChartAxis {
  std::string label;
  double lo = 0, hi = 1;
  double fixed_step = 0;  // > 0: ticks at this step (45 deg)
  double min_step = 0;    // > 0: no finer step (1 for counts)
  bool numeric = true;
};

enum class Marker { kCircle, kSquare, kTriangle, kDiamond };
// The marker of the k-th item (cycling through the four shapes).
Marker markerFor(size_t k);
// Ten colours that tell apart (the k-th, cycling).
const std::string& paletteColour(size_t k);

class SvgChart {
 public:
  // The axes are widened to whole ticks (a numeric axis; the other keeps its range).
  SvgChart(const std::string& title, const ChartAxis& x, const ChartAxis& y);
  double px(double x) const;
  double py(double y) const;
  void dot(double x, double y, const std::string& colour, double radius = 2.2);
  void marker(double x, double y, const std::string& colour, Marker shape, double size = 2.6);
  void bar(double xa, double xb, double h, const std::string& fill = "#9ecae1",
           const std::string& stroke = "#3182bd");
  void polyline(const std::vector<std::pair<double, double>>& points, const std::string& colour);
  // A horizontal line across the plot at y, dashed, with a label at its right end.
  void level(double y, const std::string& colour, const std::string& label);
  // A label under the x axis at x, on line 0, 1, 2 below it.
  void xLabel(double x, int line, const std::string& text);
  void legend(int row, const std::string& text, const std::string& colour,
              Marker shape = Marker::kCircle);
  void note(int row, const std::string& text);
  std::string svg() const;

 private:
  void markerAt(double cx, double cy, const std::string& colour, Marker shape, double size);
  static constexpr double kLeft = 80, kRight = 680, kTop = 40, kBottom = 440;
  double x0_, x1_, y0_, y1_;
  std::string body_;
};

}  // namespace robocal::report_detail
