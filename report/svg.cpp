#include "report/svg.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace rotacal::report {

std::string escape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

const char* seriesColour(size_t i) {
  static const char* palette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                  "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};
  return palette[i % (sizeof(palette) / sizeof(palette[0]))];
}

std::vector<double> niceTicks(double lo, double hi, int target) {
  if (!(hi > lo)) {
    const double d = std::abs(lo) > 0 ? std::abs(lo) * 0.1 : 1.0;
    lo -= d;
    hi += d;
  }
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::floor(lo / step) * step; v <= hi + step * 1e-9; v += step) {
    if (v >= lo - step * 1e-9) t.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  }
  return t;
}

namespace {

std::string tickText(double v, double step) {
  const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  return fmt::format("{:.{}f}", v, std::clamp(decimals, 0, 6));
}

std::string axisTitle(const PlotAxis& a) { return escape(a.label) + " (" + escape(a.unit) + ")"; }

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(hi >= lo); }
};

}  // namespace

std::string svgPlot(const Figure& f, int width, int height) {
  Range rx, ry;
  for (const auto& s : f.series)
    for (size_t i = 0; i < s.x.size(); ++i) {
      rx.add(s.x[i]);
      const double u = s.u.empty() ? 0.0 : std::abs(s.u[i]);
      ry.add(s.y[i] - u);
      ry.add(s.y[i] + u);
    }
  for (const auto& b : f.bands)
    for (size_t i = 0; i < b.x.size(); ++i) {
      rx.add(b.x[i]);
      ry.add(b.lo[i]);
      ry.add(b.hi[i]);
    }
  if (!f.x.categories.empty()) {
    rx.add(-0.5);
    rx.add(static_cast<double>(f.x.categories.size()) - 0.5);
  }
  if (rx.empty()) rx = {0.0, 1.0};
  if (ry.empty()) ry = {0.0, 1.0};
  const auto xt = f.x.categories.empty() ? niceTicks(rx.lo, rx.hi, 6) : std::vector<double>{};
  const auto yt = niceTicks(ry.lo, ry.hi, 5);
  const double x0 = f.x.categories.empty() ? std::min(rx.lo, xt.front()) : rx.lo;
  const double x1 = f.x.categories.empty() ? std::max(rx.hi, xt.back()) : rx.hi;
  const double y0 = std::min(ry.lo, yt.front()), y1 = std::max(ry.hi, yt.back());

  const int left = 64, right = 16, top = 28, legend_h = 18 * static_cast<int>((f.series.size() + f.bands.size() + 2) / 3);
  const int bottom = 44 + legend_h;
  const double pw = width - left - right, ph = height - top - bottom;
  auto X = [&](double v) { return left + (x1 > x0 ? (v - x0) / (x1 - x0) : 0.5) * pw; };
  auto Y = [&](double v) { return top + ph - (y1 > y0 ? (v - y0) / (y1 - y0) : 0.5) * ph; };

  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" id=\"fig_{}\" width=\"{}\" height=\"{}\" "
      "viewBox=\"0 0 {} {}\" font-family=\"sans-serif\" font-size=\"11\">\n",
      escape(f.id), width, height, width, height);
  s += fmt::format("<title>{}</title>\n", escape(f.title.empty() ? f.id : f.title));
  s += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#fff\" stroke=\"#444\"/>\n", left, top, pw, ph);
  // Grid and ticks.
  const double ystep = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double v : yt) {
    s += fmt::format("<line class=\"grid\" x1=\"{}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>", left,
                     left + pw, Y(v), Y(v));
    s += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", left - 4, Y(v) + 4, tickText(v, ystep));
  }
  if (f.x.categories.empty()) {
    const double xstep = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
    for (double v : xt) {
      s += fmt::format("<line class=\"grid\" x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{}\" y2=\"{:.1f}\" stroke=\"#e4e4e4\"/>", X(v),
                       X(v), top, top + ph);
      s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", X(v), top + ph + 14,
                       tickText(v, xstep));
    }
  } else {
    for (size_t i = 0; i < f.x.categories.size(); ++i)
      s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", X(static_cast<double>(i)),
                       top + ph + 14, escape(f.x.categories[i]));
  }
  if (y0 < 0 && y1 > 0)
    s += fmt::format("<line x1=\"{}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#999\"/>\n", left, left + pw, Y(0), Y(0));
  s += fmt::format("<text class=\"axis-label\" x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n", left + pw / 2,
                   top + ph + 32, axisTitle(f.x));
  s += fmt::format(
      "<text class=\"axis-label\" x=\"14\" y=\"{:.1f}\" text-anchor=\"middle\" transform=\"rotate(-90 14 {:.1f})\">{}</text>\n",
      top + ph / 2, top + ph / 2, axisTitle(f.y));
  s += fmt::format("<text x=\"{}\" y=\"16\" font-weight=\"bold\" font-size=\"12\">{}</text>\n", left,
                   escape(f.title.empty() ? f.id : f.title));

  // Bands under the series.
  for (size_t b = 0; b < f.bands.size(); ++b) {
    const auto& band = f.bands[b];
    std::string pts;
    for (size_t i = 0; i < band.x.size(); ++i) pts += fmt::format("{:.1f},{:.1f} ", X(band.x[i]), Y(band.hi[i]));
    for (size_t i = band.x.size(); i-- > 0;) pts += fmt::format("{:.1f},{:.1f} ", X(band.x[i]), Y(band.lo[i]));
    s += fmt::format("<polygon class=\"band\" points=\"{}\" fill=\"{}\" fill-opacity=\"0.18\" stroke=\"none\"/>\n", pts,
                     seriesColour(f.series.size() + b));
  }
  for (size_t k = 0; k < f.series.size(); ++k) {
    const auto& se = f.series[k];
    const char* col = seriesColour(k);
    if (!se.u.empty())
      for (size_t i = 0; i < se.x.size(); ++i) {
        const double u = std::abs(se.u[i]);
        s += fmt::format("<line class=\"errorbar\" x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1:.1f}\" y2=\"{2:.1f}\" stroke=\"{3}\"/>",
                         X(se.x[i]), Y(se.y[i] - u), Y(se.y[i] + u), col);
      }
    if (se.style == "line" && se.x.size() > 1) {
      std::string pts;
      for (size_t i = 0; i < se.x.size(); ++i) pts += fmt::format("{:.1f},{:.1f} ", X(se.x[i]), Y(se.y[i]));
      s += fmt::format("<polyline class=\"series\" points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.6\"/>\n", pts, col);
    }
    if (se.style == "points" || se.x.size() == 1 || !se.u.empty()) {
      s += fmt::format("<g class=\"series\" fill=\"{}\">", col);
      for (size_t i = 0; i < se.x.size(); ++i)
        s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.6\"/>", X(se.x[i]), Y(se.y[i]));
      s += "</g>\n";
    }
  }
  // Legend.
  int item = 0;
  auto legend = [&](const std::string& name, const char* col, bool band) {
    const double lx = left + (item % 3) * (pw / 3), ly = height - legend_h + 4 + (item / 3) * 18;
    if (band)
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"14\" height=\"8\" fill=\"{}\" fill-opacity=\"0.3\"/>", lx, ly - 8, col);
    else
      s += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"14\" height=\"3\" fill=\"{}\"/>", lx, ly - 5, col);
    s += fmt::format("<text class=\"legend\" x=\"{:.1f}\" y=\"{:.1f}\">{}</text>\n", lx + 18, ly, escape(name));
    ++item;
  };
  for (size_t k = 0; k < f.series.size(); ++k) legend(f.series[k].name, seriesColour(k), false);
  for (size_t b = 0; b < f.bands.size(); ++b) legend(f.bands[b].name, seriesColour(f.series.size() + b), true);
  s += "</svg>\n";
  return s;
}

std::string svgProjection(const ProjectionPanel& panel, double mag, const Eigen::Vector4d& lim, double bar_um, int size) {
  const int margin_l = 48, margin_b = 36, margin_t = 22, margin_r = 10;
  const double pw = size - margin_l - margin_r, ph = size - margin_t - margin_b;
  // Equal scales on both axes: a square stays square.
  const double span = std::max(lim[1] - lim[0], lim[3] - lim[2]);
  const double cx = 0.5 * (lim[0] + lim[1]), cy = 0.5 * (lim[2] + lim[3]);
  const double k = std::min(pw, ph) / span;
  auto X = [&](double v) { return margin_l + pw / 2 + (v - cx) * k; };
  auto Y = [&](double v) { return margin_t + ph / 2 - (v - cy) * k; };
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"projection\" width=\"{0}\" height=\"{0}\" viewBox=\"0 0 {0} {0}\" "
      "font-family=\"sans-serif\" font-size=\"10\">\n",
      size);
  s += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#fff\" stroke=\"#444\"/>\n", margin_l,
                   margin_t, pw, ph);
  s += fmt::format("<text x=\"{}\" y=\"14\" font-weight=\"bold\">{}</text>\n", margin_l, escape(panel.title));
  const auto tx = niceTicks(cx - span / 2, cx + span / 2, 4), ty = niceTicks(cy - span / 2, cy + span / 2, 4);
  for (double v : tx) {
    if (X(v) < margin_l || X(v) > margin_l + pw) continue;
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>", X(v), margin_t + ph + 12,
                     tickText(v, tx.size() > 1 ? tx[1] - tx[0] : 1));
  }
  for (double v : ty) {
    if (Y(v) < margin_t || Y(v) > margin_t + ph) continue;
    s += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>", margin_l - 3, Y(v) + 3,
                     tickText(v, ty.size() > 1 ? ty[1] - ty[0] : 1));
  }
  s += fmt::format("<text class=\"axis-label\" x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{} (mm)</text>\n",
                   margin_l + pw / 2, size - 8, escape(panel.x_label));
  s += fmt::format(
      "<text class=\"axis-label\" x=\"12\" y=\"{0:.1f}\" text-anchor=\"middle\" transform=\"rotate(-90 12 {0:.1f})\">{1} (mm)</text>\n",
      margin_t + ph / 2, escape(panel.y_label));
  s += "<g class=\"nominal\" fill=\"#000\">";
  for (const auto& p : panel.points)
    s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"1.6\"/>", X(p.nominal_mm.x()), Y(p.nominal_mm.y()));
  s += "</g>\n<g class=\"measured\" fill=\"none\" stroke=\"#d62728\">";
  for (const auto& p : panel.points) {
    const Eigen::Vector2d m = p.nominal_mm + mag * 1e-3 * p.deviation_um;
    s += fmt::format("<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke-width=\"0.6\"/>", X(p.nominal_mm.x()),
                     Y(p.nominal_mm.y()), X(m.x()), Y(m.y()));
    s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\"/>", X(m.x()), Y(m.y()));
  }
  s += "</g>\n";
  // Scale bar: bar_um of deviation at this magnification.
  const double bar_px = mag * 1e-3 * bar_um * k;
  if (bar_px > 4 && bar_px < pw) {
    const double bx = margin_l + 6, by = margin_t + ph - 8;
    s += fmt::format("<line class=\"scalebar\" x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#d62728\" stroke-width=\"2\"/>",
                     bx, bx + bar_px, by, by);
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#d62728\">{} um (x{})</text>\n", bx, by - 4, bar_um, mag);
  }
  s += "</svg>\n";
  return s;
}

}  // namespace rotacal::report
