#include "svg_chart.hpp"

#include "report_parts.hpp"

namespace robocal::report_detail {

namespace {

AxisTicks ticksOf(const ChartAxis& a) {
  return niceTicks(a.lo, a.hi, 6, a.fixed_step, a.min_step);
}

}  // namespace

Marker markerFor(size_t k) {
  static constexpr Marker kOrder[] = {Marker::kCircle, Marker::kTriangle, Marker::kSquare,
                                      Marker::kDiamond};
  return kOrder[k % 4];
}

const std::string& paletteColour(size_t k) {
  static const std::vector<std::string> kPalette = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                    "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                                    "#bcbd22", "#17becf"};
  return kPalette[k % kPalette.size()];
}

SvgChart::SvgChart(const std::string& title, const ChartAxis& x, const ChartAxis& y) {
  const AxisTicks xt = ticksOf(x), yt = ticksOf(y);
  x0_ = x.numeric ? xt.first : x.lo;
  x1_ = x.numeric ? xt.last() : x.hi;
  y0_ = y.numeric ? yt.first : y.lo;
  y1_ = y.numeric ? yt.last() : y.hi;
  body_ +=
      "<text x='380' y='24' text-anchor='middle' font-size='15'>" + escapeXml(title) + "</text>\n";
  body_ += "<text x='380' y='492' text-anchor='middle' font-size='13'>" + escapeXml(x.label) +
           "</text>\n";
  body_ +=
      "<text x='18' y='240' text-anchor='middle' font-size='13' transform='rotate(-90 18 240)'>" +
      escapeXml(y.label) + "</text>\n";
  if (x.numeric)
    for (int k = 0; k < xt.count; ++k) {
      const double v = xt.value(k);
      body_ += fmt("<line x1='%.1f' y1='%g' x2='%.1f' y2='%g' stroke='#e5e5e5'/>\n", px(v), kTop,
                   px(v), kBottom);
      body_ +=
          fmt("<text x='%.1f' y='%g' text-anchor='middle' font-size='11'>", px(v), kBottom + 16) +
          xt.label(v) + "</text>\n";
    }
  if (y.numeric)
    for (int k = 0; k < yt.count; ++k) {
      const double v = yt.value(k);
      body_ += fmt("<line x1='%g' y1='%.1f' x2='%g' y2='%.1f' stroke='#e5e5e5'/>\n", kLeft, py(v),
                   kRight, py(v));
      body_ +=
          fmt("<text x='%g' y='%.1f' text-anchor='end' font-size='11'>", kLeft - 4, py(v) + 4) +
          yt.label(v) + "</text>\n";
    }
  body_ += fmt("<rect x='%g' y='%g' width='%g' height='%g' fill='none' stroke='black'/>\n", kLeft,
               kTop, kRight - kLeft, kBottom - kTop);
  if (y0_ < 0 && y1_ > 0)
    body_ += fmt("<line x1='%g' y1='%.1f' x2='%g' y2='%.1f' stroke='#999'/>\n", kLeft, py(0),
                 kRight, py(0));
}

double SvgChart::px(double x) const {
  return kLeft + (x - x0_) / (x1_ - x0_) * (kRight - kLeft);
}

double SvgChart::py(double y) const {
  return kBottom - (y - y0_) / (y1_ - y0_) * (kBottom - kTop);
}

void SvgChart::dot(double x, double y, const std::string& colour, double radius) {
  body_ +=
      fmt("<circle cx='%.1f' cy='%.1f' r='%g' fill='", px(x), py(y), radius) + colour + "'/>\n";
}

void SvgChart::markerAt(double cx, double cy, const std::string& colour, Marker shape, double s) {
  switch (shape) {
    case Marker::kCircle:
      body_ += fmt("<circle cx='%.1f' cy='%.1f' r='%g' fill='", cx, cy, s) + colour + "'/>\n";
      break;
    case Marker::kSquare:
      body_ += fmt("<rect x='%.1f' y='%.1f' width='%g' height='%g' fill='", cx - s, cy - s, 2 * s,
                   2 * s) +
               colour + "'/>\n";
      break;
    case Marker::kTriangle:
      body_ +=
          fmt("<polygon points='%.1f,%.1f %.1f,%.1f ", cx, cy - 1.3 * s, cx - 1.2 * s, cy + s) +
          fmt("%.1f,%.1f' fill='", cx + 1.2 * s, cy + s) + colour + "'/>\n";
      break;
    case Marker::kDiamond:
      body_ += fmt("<polygon points='%.1f,%.1f %.1f,%.1f ", cx, cy - 1.4 * s, cx + 1.4 * s, cy) +
               fmt("%.1f,%.1f %.1f,%.1f' fill='", cx, cy + 1.4 * s, cx - 1.4 * s, cy) + colour +
               "'/>\n";
      break;
  }
}

void SvgChart::marker(double x, double y, const std::string& colour, Marker shape, double size) {
  markerAt(px(x), py(y), colour, shape, size);
}

void SvgChart::bar(double xa, double xb, double h, const std::string& fill,
                   const std::string& stroke) {
  body_ += fmt("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' ", px(xa), py(h),
               px(xb) - px(xa), py(0) - py(h)) +
           "fill='" + fill + "' stroke='" + stroke + "'/>\n";
}

void SvgChart::polyline(const std::vector<std::pair<double, double>>& points,
                        const std::string& colour) {
  body_ += "<polyline fill='none' stroke-width='2' stroke='" + colour + "' points='";
  for (const auto& [x, y] : points) body_ += fmt("%.1f,%.1f ", px(x), py(y));
  body_ += "'/>\n";
}

void SvgChart::level(double y, const std::string& colour, const std::string& label) {
  body_ += fmt("<line x1='%g' y1='%.1f' x2='%g' y2='%.1f' stroke-dasharray='6 4' ", kLeft, py(y),
               kRight, py(y)) +
           "stroke='" + colour + "'/>\n";
  body_ += fmt("<text x='%g' y='%.1f' font-size='11' fill='", kRight + 6, py(y) + 4) + colour +
           "'>" + escapeXml(label) + "</text>\n";
}

void SvgChart::xLabel(double x, int line, const std::string& text) {
  body_ += fmt("<text x='%.1f' y='%g' text-anchor='middle' font-size='10'>", px(x),
               kBottom + 14 + 12 * line) +
           escapeXml(text) + "</text>\n";
}

void SvgChart::legend(int row, const std::string& text, const std::string& colour, Marker shape) {
  const double y = kTop + 14 + 15 * row;
  markerAt(kRight + 14, y - 4, colour, shape, 4);
  body_ +=
      fmt("<text x='%g' y='%g' font-size='11'>", kRight + 24, y) + escapeXml(text) + "</text>\n";
}

void SvgChart::note(int row, const std::string& text) {
  body_ += fmt("<text x='%g' y='%g' font-size='12'>", kLeft + 8, kTop + 18 + 16 * row) +
           escapeXml(text) + "</text>\n";
}

std::string SvgChart::svg() const {
  return "<svg xmlns='http://www.w3.org/2000/svg' width='900' height='500' "
         "viewBox='0 0 900 500' font-family='sans-serif'>\n"
         "<rect width='900' height='500' fill='white'/>\n" +
         body_ + "</svg>\n";
}

}  // namespace robocal::report_detail
