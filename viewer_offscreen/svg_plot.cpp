#include "viewer_offscreen/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "viewer_offscreen/top_down.h"

namespace voxplan {
namespace {

std::string Fmt(double v, int decimals = 2) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Hex(uint32_t rgbx) {
  char buf[8];
  std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", Red(rgbx), Green(rgbx), Blue(rgbx));
  return buf;
}

// Tick labels with as many decimals as the step needs.
int TickDecimals(const std::vector<double>& ticks) {
  if (ticks.size() < 2) return 0;
  const double step = ticks[1] - ticks[0];
  return std::clamp(int(std::ceil(-std::log10(step) - 1e-9)), 0, 6);
}

// The document's opening: size, white background, the title centred on top.
std::string SvgOpen(double w, double h, const std::string& title) {
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + Fmt(w, 0) +
                    "\" height=\"" + Fmt(h, 0) + "\" viewBox=\"0 0 " + Fmt(w, 0) + " " + Fmt(h, 0) +
                    "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<text x=\"" + Fmt(w / 2, 1) + "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">" +
         Escape(title) + "</text>\n";
  return svg;
}

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, int count) {
  if (!(hi > lo) || count < 1) return {lo};
  const double raw = (hi - lo) / count;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * mag;
  for (double m : {1.0, 2.0, 5.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  // Multiples of the step, each computed from its integer index so no error accumulates.
  std::vector<double> ticks;
  const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
  for (double k = first; k <= last; k += 1.0) ticks.push_back(k == 0.0 ? 0.0 : k * step);
  return ticks;
}

Result<std::string> SvgLinePlot(const std::vector<PlotSeries>& series, const PlotParams& params) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double x_lo = kInf, x_hi = -kInf, y_lo = kInf, y_hi = -kInf;
  for (const PlotSeries& s : series) {
    if (s.x.size() != s.y.size())
      return InvalidArgument("plot series '" + s.name + "' has " + std::to_string(s.x.size()) +
                             " x values and " + std::to_string(s.y.size()) + " y values");
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_lo = std::min(x_lo, s.x[i]), x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]), y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (!(x_lo <= x_hi)) return InvalidArgument("plot '" + params.title + "' has no finite point");
  if (params.y_min < params.y_max) y_lo = params.y_min, y_hi = params.y_max;
  if (x_hi == x_lo) x_hi = x_lo + 1.0;
  if (y_hi == y_lo) y_hi = y_lo + 1.0;
  const std::vector<double> x_ticks = NiceTicks(x_lo, x_hi, 6);
  const std::vector<double> y_ticks = NiceTicks(y_lo, y_hi, 5);
  x_lo = std::min(x_lo, x_ticks.front()), x_hi = std::max(x_hi, x_ticks.back());
  y_lo = std::min(y_lo, y_ticks.front()), y_hi = std::max(y_hi, y_ticks.back());

  const double w = params.width_px, h = params.height_px;
  const double left = 70, right = w - 150, top = 40, bottom = h - 50;  // legend on the right
  auto px = [&](double x) { return left + (x - x_lo) / (x_hi - x_lo) * (right - left); };
  auto py = [&](double y) { return bottom - (y - y_lo) / (y_hi - y_lo) * (bottom - top); };

  std::string svg = SvgOpen(w, h, params.title);
  const int x_dec = TickDecimals(x_ticks), y_dec = TickDecimals(y_ticks);
  for (double t : y_ticks) {
    const std::string y = Fmt(py(t), 1);
    svg += "<line x1=\"" + Fmt(left, 1) + "\" y1=\"" + y + "\" x2=\"" + Fmt(right, 1) + "\" y2=\"" +
           y + "\" stroke=\"#e0e0e0\"/>\n";
    svg += "<text x=\"" + Fmt(left - 6, 1) + "\" y=\"" + y +
           "\" text-anchor=\"end\" dominant-baseline=\"middle\">" + Fmt(t, y_dec) + "</text>\n";
  }
  for (double t : x_ticks) {
    const std::string x = Fmt(px(t), 1);
    svg += "<line x1=\"" + x + "\" y1=\"" + Fmt(top, 1) + "\" x2=\"" + x + "\" y2=\"" +
           Fmt(bottom, 1) + "\" stroke=\"#e0e0e0\"/>\n";
    svg += "<text x=\"" + x + "\" y=\"" + Fmt(bottom + 16, 1) + "\" text-anchor=\"middle\">" +
           Fmt(t, x_dec) + "</text>\n";
  }
  svg += "<rect x=\"" + Fmt(left, 1) + "\" y=\"" + Fmt(top, 1) + "\" width=\"" +
         Fmt(right - left, 1) + "\" height=\"" + Fmt(bottom - top, 1) +
         "\" fill=\"none\" stroke=\"#404040\"/>\n";
  svg += "<text x=\"" + Fmt((left + right) / 2, 1) + "\" y=\"" + Fmt(h - 12, 1) +
         "\" text-anchor=\"middle\">" + Escape(params.x_label) + "</text>\n";
  svg += "<text transform=\"translate(16 " + Fmt((top + bottom) / 2, 1) +
         ") rotate(-90)\" text-anchor=\"middle\">" + Escape(params.y_label) + "</text>\n";

  for (size_t k = 0; k < series.size(); ++k) {
    const PlotSeries& s = series[k];
    const std::string color = Hex(RobotColor(k));
    std::string points;
    auto flush = [&] {
      if (!points.empty())
        svg += "<polyline fill=\"none\" stroke=\"" + color + "\" stroke-width=\"2\" points=\"" +
               points + "\"/>\n";
      points.clear();
    };
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        flush();
        continue;
      }
      if (!points.empty()) points += ' ';
      points += Fmt(px(s.x[i]));
      points += ',';
      points += Fmt(py(std::clamp(s.y[i], y_lo, y_hi)));
    }
    flush();
    const double ly = top + 10 + 20 * double(k);
    svg += "<line x1=\"" + Fmt(right + 12, 1) + "\" y1=\"" + Fmt(ly, 1) + "\" x2=\"" +
           Fmt(right + 36, 1) + "\" y2=\"" + Fmt(ly, 1) + "\" stroke=\"" + color +
           "\" stroke-width=\"2\"/>\n";
    svg += "<text x=\"" + Fmt(right + 42, 1) + "\" y=\"" + Fmt(ly, 1) +
           "\" dominant-baseline=\"middle\">" + Escape(s.name) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

Result<std::string> SvgTimeline(const std::vector<TimelineRow>& rows,
                                const TimelineParams& params) {
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
  for (const TimelineRow& row : rows)
    for (const TimelineSpan& s : row.spans) {
      if (!std::isfinite(s.t0_s) || !std::isfinite(s.t1_s) || s.t1_s < s.t0_s)
        return InvalidArgument("timeline row '" + row.name + "' has a span with bad times");
      if (s.category < 0 || size_t(s.category) >= params.categories.size())
        return InvalidArgument("timeline row '" + row.name + "' has a span of unknown category " +
                               std::to_string(s.category));
      t_lo = std::min(t_lo, s.t0_s), t_hi = std::max(t_hi, s.t1_s);
    }
  if (!(t_lo <= t_hi)) return InvalidArgument("timeline '" + params.title + "' has no span");
  if (t_hi == t_lo) t_hi = t_lo + 1.0;
  const std::vector<double> ticks = NiceTicks(t_lo, t_hi, 6);
  t_lo = std::min(t_lo, ticks.front()), t_hi = std::max(t_hi, ticks.back());

  const double w = params.width_px, row_h = params.row_px;
  const double left = 60, right = w - 150, top = 40;
  const double bottom = top + row_h * double(std::max<size_t>(rows.size(), 1));
  const double h = bottom + 50;
  auto px = [&](double t) { return left + (t - t_lo) / (t_hi - t_lo) * (right - left); };
  std::string svg = SvgOpen(w, h, params.title);
  const int dec = TickDecimals(ticks);
  for (double t : ticks) {
    const std::string x = Fmt(px(t), 1);
    svg += "<line x1=\"" + x + "\" y1=\"" + Fmt(top, 1) + "\" x2=\"" + x + "\" y2=\"" +
           Fmt(bottom, 1) + "\" stroke=\"#e0e0e0\"/>\n";
    svg += "<text x=\"" + x + "\" y=\"" + Fmt(bottom + 16, 1) + "\" text-anchor=\"middle\">" +
           Fmt(t, dec) + "</text>\n";
  }
  for (size_t k = 0; k < rows.size(); ++k) {
    const double y = top + row_h * double(k);
    svg += "<text x=\"" + Fmt(left - 6, 1) + "\" y=\"" + Fmt(y + row_h / 2, 1) +
           "\" text-anchor=\"end\" dominant-baseline=\"middle\">" + Escape(rows[k].name) +
           "</text>\n";
    for (const TimelineSpan& s : rows[k].spans) {
      if (s.t1_s <= s.t0_s) continue;
      svg += "<rect x=\"" + Fmt(px(s.t0_s)) + "\" y=\"" + Fmt(y + 3, 1) + "\" width=\"" +
             Fmt(px(s.t1_s) - px(s.t0_s)) + "\" height=\"" + Fmt(row_h - 6, 1) + "\" fill=\"" +
             Hex(params.categories[size_t(s.category)].rgbx) + "\"/>\n";
    }
  }
  svg += "<rect x=\"" + Fmt(left, 1) + "\" y=\"" + Fmt(top, 1) + "\" width=\"" +
         Fmt(right - left, 1) + "\" height=\"" + Fmt(bottom - top, 1) +
         "\" fill=\"none\" stroke=\"#404040\"/>\n";
  svg += "<text x=\"" + Fmt((left + right) / 2, 1) + "\" y=\"" + Fmt(h - 12, 1) +
         "\" text-anchor=\"middle\">" + Escape(params.x_label) + "</text>\n";
  for (size_t k = 0; k < params.categories.size(); ++k) {
    const double ly = top + 10 + 20 * double(k);
    svg += "<rect x=\"" + Fmt(right + 12, 1) + "\" y=\"" + Fmt(ly - 6, 1) +
           "\" width=\"24\" height=\"12\" fill=\"" + Hex(params.categories[k].rgbx) + "\"/>\n";
    svg += "<text x=\"" + Fmt(right + 42, 1) + "\" y=\"" + Fmt(ly, 1) +
           "\" dominant-baseline=\"middle\">" + Escape(params.categories[k].name) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace voxplan
