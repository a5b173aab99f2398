// bench/svgplot.cpp -- SVG line and bar charts (svgplot.h).
#include "bench/svgplot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ldc::plot {
namespace {

std::string esc(const std::string& s) {
  std::string o;
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

std::string f(double v) {  // a coordinate
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

bool usable(double v, bool log) { return std::isfinite(v) && (!log || v > 0); }

double nice_step(double raw) {
  if (!(raw > 0)) return 1;
  double p = std::pow(10.0, std::floor(std::log10(raw)));
  double m = raw / p;
  return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
}

// An axis: data range widened to ticks, and the mapping to pixels.
struct Axis {
  bool log = false;
  double lo = 0, hi = 1;
  std::vector<double> major;
  double t(double v) const { return log ? std::log10(v) : v; }
  double frac(double v) const { return (t(v) - t(lo)) / (t(hi) - t(lo)); }

  void fit(double mn, double mx, bool is_log, bool from_zero) {
    log = is_log;
    if (!(mn <= mx)) { mn = is_log ? 1 : 0; mx = is_log ? 10 : 1; }
    if (log) {
      lo = std::pow(10.0, std::floor(std::log10(mn)));
      hi = std::pow(10.0, std::ceil(std::log10(mx)));
      if (hi <= lo) hi = lo * 10;
    } else {
      if (from_zero && mn > 0) mn = 0;
      if (mx == mn) { mx = mn + 1; }
      double step = nice_step((mx - mn) / 6);
      lo = std::floor(mn / step) * step;
      hi = std::ceil(mx / step) * step;
    }
    major = ticks(lo, hi, log);
  }
};

const char* kFont = "font-family=\"DejaVu Sans, Arial, sans-serif\"";

struct Frame {
  int W, H, left = 84, right = 210, top = 46, bottom = 74;
  int pw() const { return W - left - right; }
  int ph() const { return H - top - bottom; }
};

void header(std::string& o, const Frame& fr, const std::string& title) {
  o += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(fr.W) + "\" height=\"" +
       std::to_string(fr.H) + "\" viewBox=\"0 0 " + std::to_string(fr.W) + " " + std::to_string(fr.H) + "\">\n";
  o += "<rect x=\"0\" y=\"0\" width=\"" + std::to_string(fr.W) + "\" height=\"" + std::to_string(fr.H) +
       "\" fill=\"white\"/>\n";
  o += "<text x=\"" + f(fr.left + fr.pw() / 2.0) + "\" y=\"26\" text-anchor=\"middle\" font-size=\"16\" " + kFont +
       " font-weight=\"bold\">" + esc(title) + "</text>\n";
}

void y_axis(std::string& o, const Frame& fr, const Axis& ay, const std::string& label) {
  for (double v : ay.major) {
    double y = fr.top + fr.ph() * (1 - ay.frac(v));
    o += "<line x1=\"" + f(fr.left) + "\" y1=\"" + f(y) + "\" x2=\"" + f(fr.left + fr.pw()) + "\" y2=\"" + f(y) +
         "\" stroke=\"#dddddd\" stroke-width=\"1\"/>\n";
    o += "<line x1=\"" + f(fr.left - 5) + "\" y1=\"" + f(y) + "\" x2=\"" + f(fr.left) + "\" y2=\"" + f(y) +
         "\" stroke=\"black\"/>\n";
    o += "<text x=\"" + f(fr.left - 8) + "\" y=\"" + f(y + 4) + "\" text-anchor=\"end\" font-size=\"12\" " + kFont +
         ">" + esc(tick_label(v)) + "</text>\n";
  }
  if (ay.log) {  // minor ticks at 2..9 of each decade
    for (double d = ay.lo; d < ay.hi; d *= 10)
      for (int k = 2; k <= 9; k++) {
        double v = d * k, y = fr.top + fr.ph() * (1 - ay.frac(v));
        o += "<line x1=\"" + f(fr.left - 3) + "\" y1=\"" + f(y) + "\" x2=\"" + f(fr.left) + "\" y2=\"" + f(y) +
             "\" stroke=\"black\"/>\n";
      }
  }
  double cy = fr.top + fr.ph() / 2.0;
  o += "<text x=\"18\" y=\"" + f(cy) + "\" text-anchor=\"middle\" font-size=\"13\" " + kFont +
       " transform=\"rotate(-90 18 " + f(cy) + ")\">" + esc(label) + "</text>\n";
}

void frame_lines(std::string& o, const Frame& fr) {
  o += "<line x1=\"" + f(fr.left) + "\" y1=\"" + f(fr.top) + "\" x2=\"" + f(fr.left) + "\" y2=\"" +
       f(fr.top + fr.ph()) + "\" stroke=\"black\" stroke-width=\"1.5\"/>\n";
  o += "<line x1=\"" + f(fr.left) + "\" y1=\"" + f(fr.top + fr.ph()) + "\" x2=\"" + f(fr.left + fr.pw()) + "\" y2=\"" +
       f(fr.top + fr.ph()) + "\" stroke=\"black\" stroke-width=\"1.5\"/>\n";
}

void legend(std::string& o, const Frame& fr, const std::vector<Series>& ss, bool bars) {
  double x = fr.left + fr.pw() + 16, y = fr.top + 8;
  for (size_t i = 0; i < ss.size(); i++) {
    const Series& s = ss[i];
    std::string col = s.color.empty() ? palette()[i % palette().size()] : s.color;
    double yy = y + 20.0 * i;
    if (bars) {
      o += "<rect x=\"" + f(x) + "\" y=\"" + f(yy - 9) + "\" width=\"22\" height=\"12\" fill=\"" + col + "\"/>\n";
    } else {
      if (s.line)
        o += "<line x1=\"" + f(x) + "\" y1=\"" + f(yy - 4) + "\" x2=\"" + f(x + 22) + "\" y2=\"" + f(yy - 4) +
             "\" stroke=\"" + col + "\" stroke-width=\"2\"" + (s.dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>\n";
      if (s.markers) o += "<circle cx=\"" + f(x + 11) + "\" cy=\"" + f(yy - 4) + "\" r=\"3\" fill=\"" + col + "\"/>\n";
    }
    o += "<text x=\"" + f(x + 28) + "\" y=\"" + f(yy) + "\" font-size=\"12\" " + kFont + ">" + esc(s.name) +
         "</text>\n";
  }
}

void note(std::string& o, const Frame& fr, const std::string& text) {
  if (text.empty()) return;
  o += "<text x=\"" + f(fr.left) + "\" y=\"" + f(fr.H - 8) + "\" font-size=\"10\" fill=\"#555555\" " + kFont + ">" +
       esc(text) + "</text>\n";
}

}  // namespace

const std::vector<std::string>& palette() {
  static const std::vector<std::string> p = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                             "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  return p;
}

std::vector<double> ticks(double lo, double hi, bool log) {
  std::vector<double> t;
  if (log) {
    if (!(lo > 0) || !(hi > lo)) return t;
    double decades = std::log10(hi / lo);
    for (double d = lo; d <= hi * 1.0001; d *= 10) {
      t.push_back(d);
      if (decades <= 2.01 && d * 10 <= hi * 1.0001) {
        t.push_back(d * 2);
        t.push_back(d * 5);
      }
    }
    std::sort(t.begin(), t.end());
    return t;
  }
  if (!(hi > lo)) return {lo};
  double step = nice_step((hi - lo) / 6);
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-6; v += step)
    t.push_back(std::fabs(v) < step * 1e-9 ? 0 : v);
  return t;
}

std::string tick_label(double v) {
  char b[32];
  double a = std::fabs(v);
  if (a >= 1e6) std::snprintf(b, sizeof b, "%gM", v / 1e6);
  else if (a >= 1e4) std::snprintf(b, sizeof b, "%gk", v / 1e3);
  else std::snprintf(b, sizeof b, "%g", v);
  return b;
}

std::string render(const LinePlot& p) {
  Frame fr{p.width, p.height};
  double xmn = std::numeric_limits<double>::infinity(), xmx = -xmn, ymn = xmn, ymx = -xmn;
  for (const Series& s : p.series)
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); i++) {
      if (!usable(s.x[i], p.logx) || !usable(s.y[i], p.logy)) continue;
      xmn = std::min(xmn, s.x[i]); xmx = std::max(xmx, s.x[i]);
      ymn = std::min(ymn, s.y[i]); ymx = std::max(ymx, s.y[i]);
    }
  Axis ax, ay;
  ax.fit(xmn, xmx, p.logx, false);
  ay.fit(ymn, ymx, p.logy, true);
  std::string o;
  header(o, fr, p.title);
  y_axis(o, fr, ay, p.ylabel);
  for (double v : ax.major) {
    double x = fr.left + fr.pw() * ax.frac(v);
    o += "<line x1=\"" + f(x) + "\" y1=\"" + f(fr.top) + "\" x2=\"" + f(x) + "\" y2=\"" + f(fr.top + fr.ph()) +
         "\" stroke=\"#eeeeee\" stroke-width=\"1\"/>\n";
    o += "<line x1=\"" + f(x) + "\" y1=\"" + f(fr.top + fr.ph()) + "\" x2=\"" + f(x) + "\" y2=\"" +
         f(fr.top + fr.ph() + 5) + "\" stroke=\"black\"/>\n";
    o += "<text x=\"" + f(x) + "\" y=\"" + f(fr.top + fr.ph() + 20) + "\" text-anchor=\"middle\" font-size=\"12\" " +
         kFont + ">" + esc(tick_label(v)) + "</text>\n";
  }
  if (ax.log)
    for (double d = ax.lo; d < ax.hi; d *= 10)
      for (int k = 2; k <= 9; k++) {
        double x = fr.left + fr.pw() * ax.frac(d * k);
        o += "<line x1=\"" + f(x) + "\" y1=\"" + f(fr.top + fr.ph()) + "\" x2=\"" + f(x) + "\" y2=\"" +
             f(fr.top + fr.ph() + 3) + "\" stroke=\"black\"/>\n";
      }
  o += "<text x=\"" + f(fr.left + fr.pw() / 2.0) + "\" y=\"" + f(fr.top + fr.ph() + 44) +
       "\" text-anchor=\"middle\" font-size=\"13\" " + kFont + ">" + esc(p.xlabel) + "</text>\n";
  frame_lines(o, fr);
  for (size_t si = 0; si < p.series.size(); si++) {
    const Series& s = p.series[si];
    std::string col = s.color.empty() ? palette()[si % palette().size()] : s.color;
    std::string pts;
    std::vector<std::pair<double, double>> xy;
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); i++) {
      if (!usable(s.x[i], p.logx) || !usable(s.y[i], p.logy)) continue;
      double x = fr.left + fr.pw() * ax.frac(s.x[i]), y = fr.top + fr.ph() * (1 - ay.frac(s.y[i]));
      xy.push_back({x, y});
      pts += (pts.empty() ? "" : " ") + f(x) + "," + f(y);
    }
    if (s.line && xy.size() > 1)
      o += "<polyline points=\"" + pts + "\" fill=\"none\" stroke=\"" + col + "\" stroke-width=\"2\"" +
           (s.dashed ? " stroke-dasharray=\"6 4\"" : "") + "/>\n";
    if (s.markers)
      for (auto [x, y] : xy) o += "<circle cx=\"" + f(x) + "\" cy=\"" + f(y) + "\" r=\"3\" fill=\"" + col + "\"/>\n";
  }
  legend(o, fr, p.series, false);
  note(o, fr, p.note);
  o += "</svg>\n";
  return o;
}

std::string render(const BarPlot& p) {
  Frame fr{p.width, p.height};
  fr.bottom = 96;
  double ymn = std::numeric_limits<double>::infinity(), ymx = -ymn;
  for (const Series& s : p.series)
    for (double v : s.y)
      if (usable(v, p.logy)) { ymn = std::min(ymn, v); ymx = std::max(ymx, v); }
  Axis ay;
  ay.fit(ymn, ymx, p.logy, true);
  std::string o;
  header(o, fr, p.title);
  y_axis(o, fr, ay, p.ylabel);
  size_t nc = p.categories.size(), ns = p.series.size();
  double slot = nc ? double(fr.pw()) / nc : fr.pw();
  double bw = ns ? slot * 0.8 / ns : slot;
  double base = fr.top + fr.ph();
  for (size_t c = 0; c < nc; c++) {
    double x0 = fr.left + slot * c + slot * 0.1;
    for (size_t si = 0; si < ns; si++) {
      const Series& s = p.series[si];
      if (c >= s.y.size() || !usable(s.y[c], p.logy)) continue;
      std::string col = s.color.empty() ? palette()[si % palette().size()] : s.color;
      double y = fr.top + fr.ph() * (1 - ay.frac(s.y[c]));
      o += "<rect x=\"" + f(x0 + bw * si) + "\" y=\"" + f(y) + "\" width=\"" + f(bw * 0.92) + "\" height=\"" +
           f(std::max(0.0, base - y)) + "\" fill=\"" + col + "\"><title>" + esc(s.name + " " + p.categories[c]) +
           ": " + tick_label(s.y[c]) + "</title></rect>\n";
    }
    double cx = fr.left + slot * (c + 0.5);
    o += "<text x=\"" + f(cx) + "\" y=\"" + f(base + 18) + "\" text-anchor=\"end\" font-size=\"12\" " + kFont +
         " transform=\"rotate(-30 " + f(cx) + " " + f(base + 18) + ")\">" + esc(p.categories[c]) + "</text>\n";
  }
  frame_lines(o, fr);
  legend(o, fr, p.series, true);
  note(o, fr, p.note);
  o += "</svg>\n";
  return o;
}

}  // namespace ldc::plot
