#include "worker/pipeline/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "worker/pipeline/html_text.h"

namespace keel::pipeline::svg {

namespace {

constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr int kLeft = 72, kRight = 16, kTop = 34, kBottom = 46;

const char* colour(size_t i) { return kColours[i % (sizeof kColours / sizeof kColours[0])]; }

// Tick labels: the shortest of %g (ticks are round numbers: "0.05", "2000", "1e+06").
std::string tick_label(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

std::string px(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f", value);
  return buffer;
}

// A data range, widened so that it is never empty.
struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v, bool log) {
    if (!std::isfinite(v) || (log && v <= 0.0)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(lo <= hi); }
  // Log ranges to whole decades; linear ranges out to the nearest ticks (`round`).
  void settle(bool log, bool round = true) {
    if (empty()) lo = log ? 1.0 : 0.0, hi = log ? 10.0 : 1.0;
    if (log) {
      lo = std::pow(10.0, std::floor(std::log10(lo)));
      hi = std::pow(10.0, std::ceil(std::log10(hi)));
      if (hi <= lo) hi = lo * 10.0;
      return;
    }
    if (hi <= lo) {
      const double pad = lo == 0.0 ? 1.0 : std::fabs(lo) * 0.1;
      lo -= pad, hi += pad;
    }
    if (!round) return;
    const double step = nice_step(hi - lo);
    lo = std::floor(lo / step + 1e-9) * step;
    hi = std::ceil(hi / step - 1e-9) * step;
  }

  // Tick step of about (hi - lo) / 5 rounded to 1, 2 or 5 times a power of ten.
  static double nice_step(double span) {
    const double raw = span / 5.0;
    const double power = std::pow(10.0, std::floor(std::log10(raw)));
    for (const double m : {1.0, 2.0, 5.0})
      if (raw <= m * power) return m * power;
    return 10.0 * power;
  }
};

std::vector<double> ticks(const Range& r, bool log) {
  std::vector<double> out;
  if (log) {
    for (double v = r.lo; v <= r.hi * 1.0000001; v *= 10.0) out.push_back(v);
    return out;
  }
  const double step = Range::nice_step(r.hi - r.lo);
  for (double v = std::ceil(r.lo / step) * step; v <= r.hi + step * 1e-9; v += step)
    out.push_back(std::fabs(v) < step * 1e-9 ? 0.0 : v);
  return out;
}

// The plotting area and the mapping of data to pixels.
class Frame {
 public:
  // `round_x`: widen x to whole ticks (not for time or category axes, which start at 0 anyway).
  Frame(const Plot& plot, Range x, Range y, bool round_x = true) : plot_(plot), x_(x), y_(y) {
    x_.settle(plot.x.log, round_x);
    y_.settle(plot.y.log);
  }
  double px_x(double v) const { return kLeft + fraction(v, x_, plot_.x.log) * inner_width(); }
  double px_y(double v) const {
    return kTop + (1.0 - fraction(v, y_, plot_.y.log)) * inner_height();
  }
  double inner_width() const { return plot_.width - kLeft - kRight; }
  double inner_height() const { return plot_.height - kTop - kBottom; }
  const Range& x() const { return x_; }
  const Range& y() const { return y_; }
  bool visible(double x, double y) const {
    return std::isfinite(x) && std::isfinite(y) && (!plot_.x.log || x > 0) &&
           (!plot_.y.log || y > 0);
  }

  // The frame, grid lines, tick labels and axis labels; `x_ticks` false for category axes.
  std::string axes(bool x_ticks = true) const {
    std::string s;
    for (double t : ticks(y_, plot_.y.log)) {
      const std::string y = px(px_y(t));
      s += "<line x1=\"" + px(kLeft) + "\" y1=\"" + y + "\" x2=\"" + px(kLeft + inner_width()) +
           "\" y2=\"" + y + "\" stroke=\"#ddd\"/>";
      s += "<text x=\"" + px(kLeft - 6) + "\" y=\"" + y +
           "\" text-anchor=\"end\" dominant-baseline=\"middle\">" + tick_label(t) + "</text>";
    }
    if (x_ticks)
      for (double t : ticks(x_, plot_.x.log)) {
        const std::string x = px(px_x(t));
        s += "<line x1=\"" + x + "\" y1=\"" + px(kTop + inner_height()) + "\" x2=\"" + x +
             "\" y2=\"" + px(kTop + inner_height() + 4) + "\" stroke=\"#555\"/>";
        s += "<text x=\"" + x + "\" y=\"" + px(kTop + inner_height() + 16) +
             "\" text-anchor=\"middle\">" + tick_label(t) + "</text>";
      }
    s += "<rect x=\"" + px(kLeft) + "\" y=\"" + px(kTop) + "\" width=\"" + px(inner_width()) +
         "\" height=\"" + px(inner_height()) + "\" fill=\"none\" stroke=\"#555\"/>";
    s += "<text x=\"" + px(kLeft + inner_width() / 2) + "\" y=\"" + px(plot_.height - 8) +
         "\" text-anchor=\"middle\">" + html::escape(plot_.x.label) + "</text>";
    s += "<text transform=\"translate(14 " + px(kTop + inner_height() / 2) +
         ") rotate(-90)\" text-anchor=\"middle\">" + html::escape(plot_.y.label) + "</text>";
    return s;
  }

 private:
  static double fraction(double v, const Range& r, bool log) {
    if (log) return (std::log10(v) - std::log10(r.lo)) / (std::log10(r.hi) - std::log10(r.lo));
    return (v - r.lo) / (r.hi - r.lo);
  }
  const Plot& plot_;
  Range x_, y_;
};

std::string open_svg(const Plot& plot) {
  return "<svg class=\"plot\" width=\"" + std::to_string(plot.width) + "\" height=\"" +
         std::to_string(plot.height) + "\" viewBox=\"0 0 " + std::to_string(plot.width) + " " +
         std::to_string(plot.height) + "\" role=\"img\" aria-label=\"" + html::escape(plot.title) +
         "\" font-family=\"sans-serif\" font-size=\"11\"><title>" + html::escape(plot.title) +
         "</title><text x=\"" + px(kLeft) + "\" y=\"16\" font-size=\"13\" font-weight=\"bold\">" +
         html::escape(plot.title) + "</text>";
}

// Names with their colours along the top right.
std::string legend(const Plot& plot, const std::vector<std::string>& names) {
  std::string s;
  double x = plot.width - kRight;
  for (size_t i = names.size(); i-- > 0;) {
    const double width = 18 + 6.2 * names[i].size();
    x -= width;
    s += "<rect x=\"" + px(x) + "\" y=\"" + px(kTop - 12) + "\" width=\"10\" height=\"8\" fill=\"" +
         colour(i) + "\"/><text x=\"" + px(x + 13) + "\" y=\"" + px(kTop - 4) + "\">" +
         html::escape(names[i]) + "</text>";
  }
  return s;
}

std::string empty_note(const Frame& frame) {
  return "<text x=\"" + px(kLeft + frame.inner_width() / 2) + "\" y=\"" +
         px(kTop + frame.inner_height() / 2) + "\" text-anchor=\"middle\">no data</text>";
}

}  // namespace

std::string line_chart(const Plot& plot, const std::vector<Series>& series) {
  Range x, y;
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (std::isfinite(s.y[i]) && (!plot.y.log || s.y[i] > 0)) {
        x.add(s.x[i], plot.x.log);
        y.add(s.y[i], plot.y.log);
      }
  const bool has_data = !x.empty();
  const Frame frame(plot, x, y);
  std::string out = open_svg(plot) + frame.axes();
  std::vector<std::string> names;
  for (size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    names.push_back(s.name);
    std::string points, markers;
    auto flush = [&] {
      if (!points.empty())
        out += "<polyline fill=\"none\" stroke-width=\"1.5\" stroke=\"" + std::string(colour(k)) +
               "\" points=\"" + points + "\"/>";
      points.clear();
    };
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!frame.visible(s.x[i], s.y[i])) {
        flush();
        continue;
      }
      const std::string xy = px(frame.px_x(s.x[i])) + "," + px(frame.px_y(s.y[i]));
      points += (points.empty() ? "" : " ") + xy;
      if (s.markers)
        markers += "<circle cx=\"" + px(frame.px_x(s.x[i])) + "\" cy=\"" + px(frame.px_y(s.y[i])) +
                   "\" r=\"2.5\" fill=\"" + colour(k) + "\"/>";
    }
    flush();
    out += markers;
  }
  if (!has_data) out += empty_note(frame);
  return out + legend(plot, names) + "</svg>";
}

std::string histogram_chart(const Plot& plot, const std::vector<Histogram>& histograms,
                            bool as_fraction) {
  Range x, y;
  y.add(0.0, false);
  std::vector<std::vector<double>> heights;
  for (const auto& h : histograms) {
    double total = 0.0;
    for (double c : h.counts) total += c;
    std::vector<double> values;
    for (double c : h.counts) values.push_back(as_fraction && total > 0 ? c / total : c);
    if (h.edges.size() == h.counts.size() + 1 && !h.counts.empty()) {
      for (double e : h.edges) x.add(e, plot.x.log);
      for (double v : values) y.add(v, false);
    }
    heights.push_back(std::move(values));
  }
  const bool has_data = !x.empty();
  const Frame frame(plot, x, y);
  std::string out = open_svg(plot) + frame.axes();
  std::vector<std::string> names;
  for (size_t k = 0; k < histograms.size(); ++k) {
    const Histogram& h = histograms[k];
    names.push_back(h.name);
    if (h.edges.size() != h.counts.size() + 1 || h.counts.empty()) continue;
    // A step outline: up and across each bin, from and back to zero.
    std::string points = px(frame.px_x(h.edges.front())) + "," + px(frame.px_y(0.0));
    for (size_t i = 0; i < h.counts.size(); ++i) {
      const std::string top = px(frame.px_y(heights[k][i]));
      points += " " + px(frame.px_x(h.edges[i])) + "," + top + " " +
                px(frame.px_x(h.edges[i + 1])) + "," + top;
    }
    points += " " + px(frame.px_x(h.edges.back())) + "," + px(frame.px_y(0.0));
    out += "<polyline fill=\"" + std::string(colour(k)) +
           "\" fill-opacity=\"0.15\" stroke-width=\"1.5\" stroke=\"" + colour(k) + "\" points=\"" +
           points + "\"/>";
  }
  if (!has_data) out += empty_note(frame);
  return out + legend(plot, names) + "</svg>";
}

std::string bar_chart(const Plot& plot, const std::vector<std::string>& series_names,
                      const std::vector<BarGroup>& groups) {
  Range x, y;
  x.add(0.0, false);
  x.add(static_cast<double>(std::max<size_t>(groups.size(), 1)), false);
  if (!plot.y.log) y.add(0.0, false);
  for (const auto& g : groups)
    for (double v : g.values) y.add(v, plot.y.log);
  Plot category_plot = plot;
  category_plot.x.log = false;
  const Frame frame(category_plot, x, y);
  std::string out = open_svg(plot) + frame.axes(false);
  const double group_width = frame.inner_width() / std::max<size_t>(groups.size(), 1);
  const size_t n = std::max<size_t>(series_names.size(), 1);
  const double bar_width = 0.8 * group_width / n;
  const double base = plot.y.log ? frame.px_y(frame.y().lo) : frame.px_y(0.0);
  for (size_t g = 0; g < groups.size(); ++g) {
    const double left = kLeft + g * group_width + 0.1 * group_width;
    for (size_t k = 0; k < groups[g].values.size(); ++k) {
      const double v = groups[g].values[k];
      if (!frame.visible(1.0, v)) continue;
      const double top = frame.px_y(v);
      out += "<rect x=\"" + px(left + k * bar_width) + "\" y=\"" + px(std::min(top, base)) +
             "\" width=\"" + px(bar_width * 0.92) + "\" height=\"" + px(std::fabs(base - top)) +
             "\" fill=\"" + colour(k) + "\"><title>" + html::escape(groups[g].label) + ", " +
             html::escape(k < series_names.size() ? series_names[k] : "") + ": " +
             html::format_shown(v) + "</title></rect>";
    }
    out += "<text x=\"" + px(kLeft + (g + 0.5) * group_width) + "\" y=\"" +
           px(kTop + frame.inner_height() + 16) + "\" text-anchor=\"middle\">" +
           html::escape(groups[g].label) + "</text>";
  }
  return out + legend(plot, series_names) + "</svg>";
}

std::string interval_chart(const Plot& plot, const std::vector<Interval>& intervals) {
  Range x, y;
  x.add(0.0, false);
  x.add(static_cast<double>(std::max<size_t>(intervals.size(), 1)), false);
  for (const auto& i : intervals) {
    y.add(i.value - i.sigma, false);
    y.add(i.value + i.sigma, false);
    if (i.truth) y.add(*i.truth, false);
  }
  Plot category_plot = plot;
  category_plot.x.log = category_plot.y.log = false;
  const Frame frame(category_plot, x, y);
  std::string out = open_svg(category_plot) + frame.axes(false);
  const double slot = frame.inner_width() / std::max<size_t>(intervals.size(), 1);
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Interval& i = intervals[k];
    const std::string cx = px(kLeft + (k + 0.5) * slot);
    if (std::isfinite(i.value) && std::isfinite(i.sigma)) {
      out += "<line x1=\"" + cx + "\" y1=\"" + px(frame.px_y(i.value - i.sigma)) + "\" x2=\"" + cx +
             "\" y2=\"" + px(frame.px_y(i.value + i.sigma)) + "\" stroke=\"" + colour(0) +
             "\" stroke-width=\"2\"/>";
      out += "<circle cx=\"" + cx + "\" cy=\"" + px(frame.px_y(i.value)) + "\" r=\"4\" fill=\"" +
             colour(0) + "\"/>";
    }
    if (i.truth && std::isfinite(*i.truth)) {
      const double ty = frame.px_y(*i.truth);
      out += "<line x1=\"" + px(kLeft + (k + 0.3) * slot) + "\" y1=\"" + px(ty) + "\" x2=\"" +
             px(kLeft + (k + 0.7) * slot) + "\" y2=\"" + px(ty) + "\" stroke=\"" + colour(1) +
             "\" stroke-width=\"2\"/>";
    }
    out += "<text x=\"" + cx + "\" y=\"" + px(kTop + frame.inner_height() + 16) +
           "\" text-anchor=\"middle\">" + html::escape(i.label) + "</text>";
  }
  return out + legend(category_plot, {"estimate \xC2\xB1 1 sigma", "truth"}) + "</svg>";
}

}  // namespace keel::pipeline::svg
