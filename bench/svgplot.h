// bench/svgplot.h -- small self-contained SVG charts for ldbench: line plots
// (linear or log axes, ticks, labels, legend) and grouped bar charts.
#pragma once

#include <string>
#include <vector>

namespace ldc::plot {

struct Series {
  std::string name;
  std::vector<double> x, y;  // points with y <= 0 are skipped on a log axis; NaN skipped everywhere
  std::string color;         // "" = next from the palette
  bool dashed = false;
  bool markers = true;
  bool line = true;
};

struct LinePlot {
  std::string title, xlabel, ylabel;
  bool logx = false, logy = false;
  std::vector<Series> series;
  std::string note;  // a line of small text under the plot (source, machine)
  int width = 760, height = 460;
};
std::string render(const LinePlot& p);

struct BarPlot {
  std::string title, ylabel;
  bool logy = false;
  std::vector<std::string> categories;  // groups along x
  std::vector<Series> series;           // one bar per category each; y[i] for categories[i]
  std::string note;
  int width = 760, height = 460;
};
std::string render(const BarPlot& p);

// The default colours, in order.
const std::vector<std::string>& palette();

// Tick positions for an axis over [lo, hi]: "nice" steps (1, 2, 5 x 10^k) on a
// linear axis, powers of ten (and 2, 5 between when the range is short) on a
// log axis.  Exposed for tests.
std::vector<double> ticks(double lo, double hi, bool log);
std::string tick_label(double v);  // 300, 3k, 1.5M, 0.25, 1e-3 ...

}  // namespace ldc::plot
