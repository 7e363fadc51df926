// Plots for report.html as inline SVG text: line charts, histograms, grouped bars and value +-
// sigma intervals. Pure functions of their data; no script, no external reference (no xmlns
// either: inline <svg> in HTML needs none), generic font families only. Non-finite values are
// left out (a line breaks there).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace keel::pipeline::svg {

struct Axis {
  std::string label;
  bool log = false;  // log10 scale; values <= 0 are left out
};

struct Plot {
  std::string title;
  Axis x, y;
  int width = 640;
  int height = 280;
};

struct Series {
  std::string name;
  std::vector<double> x, y;  // same length
  bool markers = false;      // a dot at each point (short series such as per-iteration figures)
};
std::string line_chart(const Plot& plot, const std::vector<Series>& series);

// Counts over bins [edges[i], edges[i+1]), edges.size() == counts.size() + 1.
struct Histogram {
  std::string name;
  std::vector<double> edges;
  std::vector<double> counts;
};
// Each histogram as a step outline; `as_fraction`: counts divided by the histogram's total, so
// distributions of different sizes compare (the y axis then reads "fraction of values").
std::string histogram_chart(const Plot& plot, const std::vector<Histogram>& histograms,
                            bool as_fraction);

// Categories along x, one bar per series in each.
struct BarGroup {
  std::string label;
  std::vector<double> values;  // one per series name
};
std::string bar_chart(const Plot& plot, const std::vector<std::string>& series_names,
                      const std::vector<BarGroup>& groups);

// An estimate with its 1-sigma interval, and the true value when known.
struct Interval {
  std::string label;
  double value = 0.0;
  double sigma = 0.0;
  std::optional<double> truth;
};
std::string interval_chart(const Plot& plot, const std::vector<Interval>& intervals);

}  // namespace keel::pipeline::svg
