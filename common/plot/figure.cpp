#include "common/plot/figure.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <variant>

namespace flume::plot {

// ------------------------------------------------------------------------------------------ colours, text

std::string Color::hex() const {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", r, g, b);
  return buf;
}

Color palette(std::size_t i) {
  // Okabe & Ito, "Color Universal Design" (2008); yellow and black last (weak on white, and black is for
  // text).
  static const std::array<Color, 8> colors{{{0, 114, 178},
                                            {230, 159, 0},
                                            {0, 158, 115},
                                            {213, 94, 0},
                                            {204, 121, 167},
                                            {86, 180, 233},
                                            {240, 228, 66},
                                            {0, 0, 0}}};
  return colors[i % colors.size()];
}

Color viridis(double t) {
  // Matplotlib's viridis (van der Walt & Smith) sampled at 9 points; linear interpolation between them is
  // indistinguishable from the 256-entry table at the sizes drawn here.
  static const std::array<Color, 9> stops{{{68, 1, 84},
                                           {71, 44, 122},
                                           {59, 81, 139},
                                           {44, 113, 142},
                                           {33, 144, 141},
                                           {39, 173, 129},
                                           {92, 200, 99},
                                           {170, 220, 50},
                                           {253, 231, 37}}};
  if (!(t > 0)) t = 0;  // NaN included
  if (t > 1) t = 1;
  double pos = t * (stops.size() - 1);
  std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(pos), stops.size() - 2);
  double f = pos - i;
  auto mix = [f](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(a + (static_cast<double>(b) - a) * f));
  };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g), mix(stops[i].b, stops[i + 1].b)};
}

std::string xml_escape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  std::size_t n = s.size();
  for (std::size_t i = 0; i < n;) {
    unsigned char c = p[i];
    if (c < 0x80) {
      switch (c) {
        case '&':
          out += "&amp;";
          break;
        case '<':
          out += "&lt;";
          break;
        case '>':
          out += "&gt;";
          break;
        case '"':
          out += "&quot;";
          break;
        case '\'':
          out += "&apos;";
          break;
        default:
          // XML 1.0 allows no control characters but tab, newline and carriage return.
          if (c >= 0x20 || c == '\t' || c == '\n' || c == '\r') out += static_cast<char>(c);
      }
      ++i;
      continue;
    }
    // Multi-byte UTF-8: copy a well-formed sequence, replace anything else by U+FFFD.
    std::size_t len = (c >= 0xC2 && c <= 0xDF)   ? 2
                      : (c >= 0xE0 && c <= 0xEF) ? 3
                      : (c >= 0xF0 && c <= 0xF4) ? 4
                                                 : 0;
    bool ok = len > 0 && i + len <= n;
    for (std::size_t k = 1; ok && k < len; ++k) ok = (p[i + k] & 0xC0) == 0x80;
    if (ok && len == 3) {
      // No overlong forms, no UTF-16 surrogates.
      ok = !(c == 0xE0 && p[i + 1] < 0xA0) && !(c == 0xED && p[i + 1] >= 0xA0);
    }
    if (ok && len == 4) ok = !(c == 0xF0 && p[i + 1] < 0x90) && !(c == 0xF4 && p[i + 1] >= 0x90);
    if (ok) {
      out.append(reinterpret_cast<const char*>(p + i), len);
      i += len;
    } else {
      out += "\xEF\xBF\xBD";
      ++i;
    }
  }
  return out;
}

namespace {

// Coordinates with two decimals (a hundredth of a pixel), locale-independent, trailing zeros dropped.
// Pixel coordinates beyond this are off any canvas (and clipped): they are drawn at it instead.
constexpr double kFarPx = 1e9;

std::string num(double v) {
  if (std::abs(v) < 0.005) return "0";
  v = std::clamp(v, -kFarPx, kFarPx);
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, 2);
  std::string s(buf, res.ptr);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s;
}

bool finite(double v) { return std::isfinite(v); }

// A tick step m x 10^e with m in {1, 2, 2.5, 5}; kept apart so that ticks are computed as (k m) / 10^-e,
// which rounds to the double nearest the decimal value (0.6, not 3 x 0.2 = 0.6000000000000001).
struct TickStep {
  double m;
  int e;
  double value() const { return at(1); }
  double at(double k) const { return e >= 0 ? k * m * std::pow(10.0, e) : k * m / std::pow(10.0, -e); }
  bool operator==(const TickStep& o) const { return m == o.m && e == o.e; }
};

TickStep step_for(double range, int target) {
  double raw = range / std::max(1, target);
  int e = static_cast<int>(std::floor(std::log10(raw)));
  double mag = std::pow(10.0, e);
  for (double m : {1.0, 2.0, 2.5, 5.0})
    if (m * mag >= raw * (1 - 1e-9)) return {m, e};
  return {1.0, e + 1};
}

// Decimal places needed to print multiples of `step` exactly.
int decimals_for(double step) {
  for (int d = 0; d < 12; ++d) {
    double scaled = step * std::pow(10.0, d);
    if (std::abs(scaled - std::round(scaled)) < 1e-6 * scaled) return d;
  }
  return 12;
}

std::string format_tick(double v, double step) {
  if (std::abs(v) < step * 1e-9) return "0";
  double a = std::abs(v);
  char buf[64];
  if (a >= 1e6 || a < 1e-4) {
    // Significant digits enough to tell neighbouring ticks apart.
    int sig = std::max(1, static_cast<int>(std::floor(std::log10(a)) - std::floor(std::log10(step))) + 2);
    std::snprintf(buf, sizeof buf, "%.*g", std::min(sig, 15), v);
  } else {
    std::snprintf(buf, sizeof buf, "%.*f", decimals_for(step), v);
  }
  std::string s = buf;
  // printf follows LC_NUMERIC; SVG needs a point.
  std::replace(s.begin(), s.end(), ',', '.');
  return s;
}

}  // namespace

// ------------------------------------------------------------------------------------------------- ticks

namespace {

// Limits are clamped to +-kHugeLimit so that a range, a step and a tick one step beyond the data stay finite
// doubles; data beyond it lie outside the axis (clipped).
constexpr double kHugeLimit = 1e307;
// A range below this many parts of its magnitude is constant up to rounding: tick labels (at most 15
// significant digits) could not tell the ticks apart, and k += 1 stops changing k near 2^53.
constexpr double kRelativeResolution = 1e-12;
// A range below this is treated as zero width: its step 10^e would need e < -307, beyond normal doubles.
constexpr double kTinyRange = 1e-290;

void clamp_limits(double& lo, double& hi) {
  if (hi < lo) std::swap(lo, hi);
  lo = std::clamp(lo, -kHugeLimit, kHugeLimit);
  hi = std::clamp(hi, -kHugeLimit, kHugeLimit);
}

bool degenerate_range(double lo, double hi) {
  return hi - lo <= std::max(kTinyRange, kRelativeResolution * std::max(std::abs(lo), std::abs(hi)));
}

// Widens a degenerate [lo, hi] to +-10 % around its centre (+-1 around zero).
void widen_degenerate(double& lo, double& hi) {
  if (!degenerate_range(lo, hi)) return;
  double c = lo + (hi - lo) / 2;
  if (std::abs(c) < kTinyRange) c = 0;
  double pad = c == 0 ? 1.0 : std::abs(c) * 0.1;
  lo = c - pad;
  hi = c + pad;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!finite(lo) || !finite(hi)) throw std::invalid_argument("plot: ticks need finite limits");
  clamp_limits(lo, hi);
  if (degenerate_range(lo, hi)) return {lo};
  TickStep step = step_for(hi - lo, target);
  double eps = step.value() * 1e-9;
  std::vector<double> ticks;
  // At most target + 2 ticks: the step is at least (hi - lo) / target, and k stays far below 2^53.
  for (double k = std::ceil((lo - eps) / step.value()); step.at(k) <= hi + eps; k += 1)
    ticks.push_back(step.at(k) + 0.0);
  return ticks;
}

NiceAxis nice_axis(double lo, double hi, int target) {
  if (!finite(lo) || !finite(hi)) throw std::invalid_argument("plot: limits need finite data");
  clamp_limits(lo, hi);
  widen_degenerate(lo, hi);
  // The step is chosen for the data range and kept: recomputing it from the widened range could pick a
  // coarser one whose ticks no longer land on the limits.
  TickStep step = step_for(hi - lo, target);
  double eps = step.value() * 1e-9;
  NiceAxis out;
  double k0 = std::floor((lo + eps) / step.value()), k1 = std::ceil((hi - eps) / step.value());
  for (double k = k0; k <= k1; k += 1) out.ticks.push_back(step.at(k) + 0.0);
  out.lo = out.ticks.front();
  out.hi = out.ticks.back();
  return out;
}

std::vector<double> log_ticks(double lo, double hi) {
  if (!(lo > 0) || !(hi > 0) || !finite(lo) || !finite(hi))
    throw std::invalid_argument("plot: log ticks need positive finite limits");
  if (hi < lo) std::swap(lo, hi);
  int d0 = static_cast<int>(std::floor(std::log10(lo) + 1e-9));
  int d1 = static_cast<int>(std::ceil(std::log10(hi) - 1e-9));
  int decades = d1 - d0;
  // Every k-th decade keeps the labels apart on wide ranges.
  int every = std::max(1, (decades + 7) / 8);
  std::vector<double> ticks;
  for (int d = d0; d <= d1; ++d) {
    for (double m : decades < 2 ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
      if (m == 1 && (d - d0) % every != 0) continue;
      double t = m * std::pow(10.0, d);
      if (t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) ticks.push_back(t);
    }
  }
  return ticks;
}

// ------------------------------------------------------------------------------------------------ artists

namespace {

enum class LineKind { kLine, kStepPre, kStepPost };

struct LineArtist {
  std::vector<double> x, y;
  LineStyle style;
  Color color;
  LineKind kind;
};
struct ScatterArtist {
  std::vector<double> x, y;
  MarkerStyle style;
  Color color;
};
struct BandArtist {
  std::vector<double> x, lo, hi;
  FillStyle style;
  Color color;
};
struct BarsArtist {
  std::vector<double> edges, heights;
  FillStyle style;
  Color color;
};
struct RefLineArtist {
  bool horizontal;
  double value;
  LineStyle style;
  Color color;
};
struct PolygonArtist {
  std::vector<double> x, y;
  FillStyle style;
  Color color;
};
struct HeatmapArtist {
  std::vector<double> xe, ye, values;
  HeatmapStyle style;
  double vmin, vmax;
};
struct TextArtist {
  double x, y;
  std::string text;
  TextStyle style;
};

using Artist = std::variant<LineArtist, ScatterArtist, BandArtist, BarsArtist, RefLineArtist, PolygonArtist,
                            HeatmapArtist, TextArtist>;

const Color kGrey{102, 102, 102};

void require_same_size(const char* what, std::size_t a, std::size_t b) {
  if (a != b)
    throw std::invalid_argument(std::string("plot: ") + what + ": sizes differ (" + std::to_string(a) +
                                " vs " + std::to_string(b) + ")");
}

std::string dasharray(Dash d, double width) {
  switch (d) {
    case Dash::kSolid:
      return "";
    case Dash::kDashed:
      return num(4 * width) + " " + num(2.5 * width);
    case Dash::kDotted:
      return num(1 * width) + " " + num(2 * width);
    case Dash::kDashDot:
      return num(4 * width) + " " + num(2 * width) + " " + num(1 * width) + " " + num(2 * width);
  }
  return "";
}

std::string stroke_attrs(const LineStyle& s, const Color& c) {
  std::string a = " fill=\"none\" stroke=\"" + c.hex() + "\" stroke-width=\"" + num(s.width) +
                  "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"";
  if (s.opacity < 1) a += " stroke-opacity=\"" + num(s.opacity) + "\"";
  std::string dash = dasharray(s.dash, s.width);
  if (!dash.empty()) a += " stroke-dasharray=\"" + dash + "\"";
  return a;
}

std::string fill_attrs(const FillStyle& s, const Color& c) {
  std::string a = " fill=\"" + c.hex() + "\"";
  if (s.opacity < 1) a += " fill-opacity=\"" + num(s.opacity) + "\"";
  if (s.edge) {
    a += " stroke=\"" + s.edge->hex() + "\" stroke-width=\"" + num(s.edge_width) + "\"";
  } else {
    a += " stroke=\"none\"";
  }
  return a;
}

// One marker centred at (x, y) as an SVG element; fill and stroke come from the enclosing group.
std::string marker_svg(Marker m, double x, double y, double size) {
  double r = size / 2;
  switch (m) {
    case Marker::kCircle:
      return "<circle cx=\"" + num(x) + "\" cy=\"" + num(y) + "\" r=\"" + num(r) + "\"/>";
    case Marker::kSquare:
      return "<rect x=\"" + num(x - r) + "\" y=\"" + num(y - r) + "\" width=\"" + num(size) + "\" height=\"" +
             num(size) + "\"/>";
    case Marker::kTriangle:
      return "<path d=\"M" + num(x) + " " + num(y - r) + "L" + num(x + r) + " " + num(y + r * 0.8) + "L" +
             num(x - r) + " " + num(y + r * 0.8) + "Z\"/>";
    case Marker::kDiamond:
      return "<path d=\"M" + num(x) + " " + num(y - r) + "L" + num(x + r) + " " + num(y) + "L" + num(x) +
             " " + num(y + r) + "L" + num(x - r) + " " + num(y) + "Z\"/>";
    case Marker::kCross:
      return "<path fill=\"none\" d=\"M" + num(x - r) + " " + num(y - r) + "L" + num(x + r) + " " +
             num(y + r) + "M" + num(x - r) + " " + num(y + r) + "L" + num(x + r) + " " + num(y - r) + "\"/>";
    case Marker::kPlus:
      return "<path fill=\"none\" d=\"M" + num(x - r) + " " + num(y) + "L" + num(x + r) + " " + num(y) + "M" +
             num(x) + " " + num(y - r) + "L" + num(x) + " " + num(y + r) + "\"/>";
  }
  return "";
}

bool stroked_marker(Marker m) { return m == Marker::kCross || m == Marker::kPlus; }

// A resolved axis: limits in transformed space (log10 for log axes) and the ticks to draw.
struct AxisView {
  Scale scale = Scale::kLinear;
  double lo = 0, hi = 1;      // transformed
  std::vector<double> ticks;  // data values
  std::vector<std::string> labels;
  std::vector<double> minor;       // data values, unlabelled
  std::vector<double> auto_ticks;  // from nice_axis when the limits were chosen automatically
  double t(double v) const { return scale == Scale::kLog ? std::log10(v) : v; }
};

// Width of a string in px at font size `size`, by a rule of thumb for sans-serif (no font metrics offline).
double text_width(const std::string& s, double size) {
  std::size_t chars = 0;
  for (unsigned char c : s) chars += (c & 0xC0) != 0x80;
  return 0.58 * size * static_cast<double>(chars);
}

}  // namespace

struct Axes::State {
  std::string title, xlabel, ylabel;
  Scale xscale = Scale::kLinear, yscale = Scale::kLinear;
  std::optional<std::pair<double, double>> xlim, ylim;
  bool equal = false;
  Legend legend = Legend::kNone;
  bool grid = true;
  std::vector<Artist> artists;
  std::size_t next_color = 0;

  Color pick(const std::optional<Color>& c) { return c ? *c : palette(next_color++); }
};

Axes::Axes() : s_(std::make_unique<State>()) {}
Axes::~Axes() = default;
Axes::Axes(Axes&&) noexcept = default;
Axes& Axes::operator=(Axes&&) noexcept = default;

Axes& Axes::title(std::string text) {
  s_->title = std::move(text);
  return *this;
}
Axes& Axes::xlabel(std::string text) {
  s_->xlabel = std::move(text);
  return *this;
}
Axes& Axes::ylabel(std::string text) {
  s_->ylabel = std::move(text);
  return *this;
}
Axes& Axes::xscale(Scale s) {
  s_->xscale = s;
  return *this;
}
Axes& Axes::yscale(Scale s) {
  s_->yscale = s;
  return *this;
}
Axes& Axes::xlim(double lo, double hi) {
  if (!finite(lo) || !finite(hi) || !(lo < hi))
    throw std::invalid_argument("plot: xlim needs finite lo < hi");
  s_->xlim = {lo, hi};
  return *this;
}
Axes& Axes::ylim(double lo, double hi) {
  if (!finite(lo) || !finite(hi) || !(lo < hi))
    throw std::invalid_argument("plot: ylim needs finite lo < hi");
  s_->ylim = {lo, hi};
  return *this;
}
Axes& Axes::equal_aspect(bool on) {
  s_->equal = on;
  return *this;
}
Axes& Axes::legend(Legend where) {
  s_->legend = where;
  return *this;
}
Axes& Axes::grid(bool on) {
  s_->grid = on;
  return *this;
}

Axes& Axes::line(const std::vector<double>& x, const std::vector<double>& y, const LineStyle& style) {
  require_same_size("line x/y", x.size(), y.size());
  s_->artists.emplace_back(LineArtist{x, y, style, s_->pick(style.color), LineKind::kLine});
  return *this;
}

Axes& Axes::scatter(const std::vector<double>& x, const std::vector<double>& y, const MarkerStyle& style) {
  require_same_size("scatter x/y", x.size(), y.size());
  s_->artists.emplace_back(ScatterArtist{x, y, style, s_->pick(style.color)});
  return *this;
}

Axes& Axes::step(const std::vector<double>& x, const std::vector<double>& y, const LineStyle& style,
                 Step where) {
  require_same_size("step x/y", x.size(), y.size());
  s_->artists.emplace_back(LineArtist{x, y, style, s_->pick(style.color),
                                      where == Step::kPre ? LineKind::kStepPre : LineKind::kStepPost});
  return *this;
}

Axes& Axes::band(const std::vector<double>& x, const std::vector<double>& lower,
                 const std::vector<double>& upper, const FillStyle& style) {
  require_same_size("band x/lower", x.size(), lower.size());
  require_same_size("band x/upper", x.size(), upper.size());
  s_->artists.emplace_back(BandArtist{x, lower, upper, style, s_->pick(style.color)});
  return *this;
}

Axes& Axes::bars(const std::vector<double>& edges, const std::vector<double>& heights,
                 const FillStyle& style) {
  if (edges.size() != heights.size() + 1)
    throw std::invalid_argument("plot: bars need one more edge than heights (" +
                                std::to_string(edges.size()) + " edges, " + std::to_string(heights.size()) +
                                " heights)");
  FillStyle s = style;
  if (s.opacity == FillStyle{}.opacity) s.opacity = 0.8;  // bars read better nearly opaque
  s_->artists.emplace_back(BarsArtist{edges, heights, s, s_->pick(style.color)});
  return *this;
}

Axes& Axes::histogram(const std::vector<double>& samples, int bins, const FillStyle& style, bool density) {
  if (bins < 1) throw std::invalid_argument("plot: histogram needs at least one bin");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  std::size_t n = 0;
  for (double v : samples) {
    if (!finite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    ++n;
  }
  if (n == 0) throw std::invalid_argument("plot: histogram of no finite samples");
  clamp_limits(lo, hi);
  widen_degenerate(lo, hi);
  std::vector<double> edges(bins + 1), counts(bins, 0.0);
  double w = (hi - lo) / bins;
  for (int i = 0; i <= bins; ++i) edges[i] = lo + w * i;
  for (double v : samples) {
    if (!finite(v)) continue;
    int b = static_cast<int>(std::clamp((v - lo) / w, 0.0, bins - 1.0));
    counts[b] += 1;
  }
  if (density)
    for (double& c : counts) c /= static_cast<double>(n) * w;
  return bars(edges, counts, style);
}

Axes& Axes::hline(double y, const LineStyle& style) {
  s_->artists.emplace_back(RefLineArtist{true, y, style, style.color.value_or(kGrey)});
  return *this;
}

Axes& Axes::vline(double x, const LineStyle& style) {
  s_->artists.emplace_back(RefLineArtist{false, x, style, style.color.value_or(kGrey)});
  return *this;
}

Axes& Axes::rect(double x0, double y0, double x1, double y1, const FillStyle& style) {
  return polygon({x0, x1, x1, x0}, {y0, y0, y1, y1}, style);
}

Axes& Axes::polygon(const std::vector<double>& x, const std::vector<double>& y, const FillStyle& style) {
  require_same_size("polygon x/y", x.size(), y.size());
  s_->artists.emplace_back(PolygonArtist{x, y, style, style.color.value_or(kGrey)});
  return *this;
}

Axes& Axes::heatmap(const std::vector<double>& x_edges, const std::vector<double>& y_edges,
                    const std::vector<double>& values, const HeatmapStyle& style) {
  if (x_edges.size() < 2 || y_edges.size() < 2)
    throw std::invalid_argument("plot: heatmap needs at least two edges per axis");
  std::size_t nx = x_edges.size() - 1, ny = y_edges.size() - 1;
  if (values.size() != nx * ny)
    throw std::invalid_argument("plot: heatmap of " + std::to_string(nx) + " x " + std::to_string(ny) +
                                " cells given " + std::to_string(values.size()) + " values");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : values)
    if (finite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!finite(lo)) lo = 0, hi = 1;
  lo = style.vmin.value_or(lo);
  hi = style.vmax.value_or(hi);
  if (!(hi > lo)) {
    if (style.vmin && style.vmax) throw std::invalid_argument("plot: heatmap needs vmin < vmax");
    hi = lo;
  }
  clamp_limits(lo, hi);
  widen_degenerate(lo, hi);
  s_->artists.emplace_back(HeatmapArtist{x_edges, y_edges, values, style, lo, hi});
  return *this;
}

Axes& Axes::text(double x, double y, std::string text, const TextStyle& style) {
  s_->artists.emplace_back(TextArtist{x, y, std::move(text), style});
  return *this;
}

// --------------------------------------------------------------------------------------------- rendering

namespace {

struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!finite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return lo > hi; }
};

std::string axis_title(const Axes::State& s) {
  return s.title.empty() ? std::string() : " '" + s.title + "'";
}

// Data extents of every artist; on log axes a non-positive value is an error (it has no position).
void data_extents(const Axes::State& s, Extent& ex, Extent& ey) {
  auto check = [&](bool is_x, double v, const char* what) {
    Scale sc = is_x ? s.xscale : s.yscale;
    if (sc == Scale::kLog && finite(v) && v <= 0) {
      std::ostringstream m;
      m << "plot: axes" << axis_title(s) << ": log " << (is_x ? "x" : "y") << " axis cannot show " << v
        << " (from " << what << "); log axes need positive data";
      throw std::invalid_argument(m.str());
    }
  };
  auto addx = [&](double v, const char* what) { check(true, v, what), ex.add(v); };
  auto addy = [&](double v, const char* what) { check(false, v, what), ey.add(v); };
  for (const Artist& a : s.artists) {
    if (auto* l = std::get_if<LineArtist>(&a)) {
      for (double v : l->x) addx(v, "a line");
      for (double v : l->y) addy(v, "a line");
    } else if (auto* p = std::get_if<ScatterArtist>(&a)) {
      for (double v : p->x) addx(v, "a scatter");
      for (double v : p->y) addy(v, "a scatter");
    } else if (auto* b = std::get_if<BandArtist>(&a)) {
      for (double v : b->x) addx(v, "a band");
      for (double v : b->lo) addy(v, "a band");
      for (double v : b->hi) addy(v, "a band");
    } else if (auto* h = std::get_if<BarsArtist>(&a)) {
      for (double v : h->edges) addx(v, "bars");
      bool any = false;
      for (double v : h->heights) {
        if (s.yscale == Scale::kLog && v == 0) continue;  // an empty bin, not drawn
        addy(v, "bars");
        any = true;
      }
      if (s.yscale == Scale::kLinear && any) ey.add(0.0);
    } else if (auto* r = std::get_if<RefLineArtist>(&a)) {
      if (r->horizontal) {
        addy(r->value, "a horizontal line");
      } else {
        addx(r->value, "a vertical line");
      }
    } else if (auto* g = std::get_if<PolygonArtist>(&a)) {
      for (double v : g->x) addx(v, "a polygon");
      for (double v : g->y) addy(v, "a polygon");
    } else if (auto* m = std::get_if<HeatmapArtist>(&a)) {
      for (double v : m->xe) addx(v, "a heatmap");
      for (double v : m->ye) addy(v, "a heatmap");
    }
  }
}

AxisView resolve_axis(Scale scale, const Extent& ex, const std::optional<std::pair<double, double>>& fixed,
                      int target) {
  AxisView v;
  v.scale = scale;
  if (scale == Scale::kLog) {
    double lo, hi;
    if (fixed) {
      if (fixed->first <= 0) throw std::invalid_argument("plot: log axis limits must be positive");
      lo = fixed->first, hi = fixed->second;
    } else if (ex.empty()) {
      lo = 1, hi = 10;
    } else {
      // Whole decades around the data.
      lo = std::pow(10.0, std::floor(std::log10(ex.lo) + 1e-9));
      hi = std::pow(10.0, std::ceil(std::log10(ex.hi) - 1e-9));
      if (hi <= lo) hi = lo * 10;
    }
    v.lo = std::log10(lo), v.hi = std::log10(hi);
    return v;
  }
  if (fixed) {
    v.lo = fixed->first, v.hi = fixed->second;
  } else if (ex.empty()) {
    v.lo = 0, v.hi = 1;
  } else {
    NiceAxis a = nice_axis(ex.lo, ex.hi, target);
    v.lo = a.lo, v.hi = a.hi;
    v.auto_ticks = a.ticks;
  }
  return v;
}

void fill_ticks(AxisView& v, int target) {
  v.ticks.clear(), v.labels.clear(), v.minor.clear();
  if (v.scale == Scale::kLog) {
    double lo = std::pow(10.0, v.lo), hi = std::pow(10.0, v.hi);
    v.ticks = log_ticks(lo, hi);
    for (double t : v.ticks) {
      double e = std::log10(t);
      if (std::abs(e - std::round(e)) < 1e-9) {
        v.labels.push_back("10^" + std::to_string(static_cast<int>(std::lround(e))));
      } else {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%g", t);
        v.labels.push_back(buf);
      }
    }
    if (v.hi - v.lo <= 6)
      for (int d = static_cast<int>(std::floor(v.lo)); d < std::ceil(v.hi); ++d)
        for (int m = 2; m <= 9; ++m) {
          double t = m * std::pow(10.0, d);
          if (t >= lo && t <= hi && std::find(v.ticks.begin(), v.ticks.end(), t) == v.ticks.end())
            v.minor.push_back(t);
        }
    return;
  }
  v.ticks = v.auto_ticks.empty() ? nice_ticks(v.lo, v.hi, target) : v.auto_ticks;
  double step = v.ticks.size() > 1 ? v.ticks[1] - v.ticks[0] : std::max(std::abs(v.lo), 1.0);
  for (double t : v.ticks) v.labels.push_back(format_tick(t, step));
}

// Tick label as SVG text content: "10^k" becomes 10 with a raised exponent.
std::string label_svg(const std::string& label) {
  auto caret = label.find('^');
  if (caret == std::string::npos) return xml_escape(label);
  return xml_escape(label.substr(0, caret)) + "<tspan dy=\"-0.45em\" font-size=\"75%\">" +
         xml_escape(label.substr(caret + 1)) + "</tspan>";
}

std::string text_svg(double x, double y, const std::string& content_svg, double size, const char* anchor,
                     const std::string& extra = "") {
  return "<text x=\"" + num(x) + "\" y=\"" + num(y) + "\" font-size=\"" + num(size) + "\" text-anchor=\"" +
         anchor + "\"" + extra + ">" + content_svg + "</text>\n";
}

const char* anchor_name(Anchor a) {
  switch (a) {
    case Anchor::kStart:
      return "start";
    case Anchor::kMiddle:
      return "middle";
    case Anchor::kEnd:
      return "end";
  }
  return "start";
}

struct LegendEntry {
  enum Kind { kLine, kMarker, kPatch };
  std::string label;
  Kind kind = kLine;
  Color color;
  LineStyle line;
  MarkerStyle marker;
  FillStyle fill;
};

// Built field by field: brace-initialising the nested styles trips GCC 12's -Wmaybe-uninitialized.
LegendEntry legend_entry(const LineStyle& l, const Color& c) {
  LegendEntry e;
  e.label = l.label, e.kind = LegendEntry::kLine, e.color = c, e.line = l;
  return e;
}
LegendEntry legend_entry(const MarkerStyle& m, const Color& c) {
  LegendEntry e;
  e.label = m.label, e.kind = LegendEntry::kMarker, e.color = c, e.marker = m;
  return e;
}
LegendEntry legend_entry(const FillStyle& f, const Color& c) {
  LegendEntry e;
  e.label = f.label, e.kind = LegendEntry::kPatch, e.color = c, e.fill = f;
  return e;
}

// Draws one axes panel into the cell (cx, cy, cw, ch). `id` makes the clip path's id unique in the figure.
void render_axes(const Axes::State& s, double cx, double cy, double cw, double ch, const std::string& id,
                 std::string& out) {
  Extent ex, ey;
  data_extents(s, ex, ey);
  const HeatmapArtist* colorbar = nullptr;
  for (const Artist& a : s.artists)
    if (auto* m = std::get_if<HeatmapArtist>(&a); m && m->style.colorbar) colorbar = m;

  // Layout in dependency order: the plot height sets the y tick count, the y tick labels the left margin,
  // and the remaining width the x tick count; limits and ticks use the same count so the limits are ticks.
  auto tick_target = [](double px_len, double px_per_tick) {
    return std::max(2, std::min(8, static_cast<int>(px_len / px_per_tick)));
  };
  const double tick_fs = 10, label_fs = 12, title_fs = 13;
  double top = s.title.empty() ? 12 : title_fs + 14;
  double bottom = 8 + tick_fs + 8 + (s.xlabel.empty() ? 0 : label_fs + 6);
  double ph = std::max(10.0, ch - top - bottom);
  AxisView yv = resolve_axis(s.yscale, ey, s.ylim, tick_target(ph, 50));
  fill_ticks(yv, tick_target(ph, 50));
  double ytick_w = 0;
  for (const auto& l : yv.labels) ytick_w = std::max(ytick_w, text_width(l, tick_fs));
  double left = 8 + (s.ylabel.empty() ? 0 : label_fs + 6) + ytick_w + 8;
  double right = 14 + (colorbar ? 70 + (colorbar->style.colorbar_label.empty() ? 0 : label_fs + 4) : 0);
  double px = cx + left, py = cy + top;
  double pw = std::max(10.0, cw - left - right);
  AxisView xv = resolve_axis(s.xscale, ex, s.xlim, tick_target(pw, 70));
  fill_ticks(xv, tick_target(pw, 70));

  if (s.equal) {
    // Shrink the plot box along the axis with fewer units per pixel, keeping it centred in its cell.
    double ux = (xv.hi - xv.lo) / pw, uy = (yv.hi - yv.lo) / ph, u = std::max(ux, uy);
    double nw = (xv.hi - xv.lo) / u, nh = (yv.hi - yv.lo) / u;
    px += (pw - nw) / 2, py += (ph - nh) / 2;
    pw = nw, ph = nh;
    fill_ticks(xv, tick_target(pw, 70));
    fill_ticks(yv, tick_target(ph, 50));
  }

  // Pixel positions clamped so that a point far outside fixed limits (clipped anyway) stays finite: the
  // difference of two such positions (a bar's width) is then a number, not inf - inf.
  auto X = [&](double v) { return std::clamp(px + (xv.t(v) - xv.lo) / (xv.hi - xv.lo) * pw, -kFarPx, kFarPx); };
  auto Y = [&](double v) {
    return std::clamp(py + ph - (yv.t(v) - yv.lo) / (yv.hi - yv.lo) * ph, -kFarPx, kFarPx);
  };
  auto ok = [&](double x, double y) {
    return finite(x) && finite(y) && (s.xscale == Scale::kLinear || x > 0) &&
           (s.yscale == Scale::kLinear || y > 0);
  };

  out += "<g class=\"axes\">\n";
  out += "<clipPath id=\"" + id + "\"><rect x=\"" + num(px) + "\" y=\"" + num(py) + "\" width=\"" + num(pw) +
         "\" height=\"" + num(ph) + "\"/></clipPath>\n";
  out += "<rect x=\"" + num(px) + "\" y=\"" + num(py) + "\" width=\"" + num(pw) + "\" height=\"" + num(ph) +
         "\" fill=\"#ffffff\" stroke=\"none\"/>\n";

  // Grid and ticks.
  std::string grid, ticks;
  for (double t : xv.ticks) {
    double x = X(t);
    if (s.grid) grid += "M" + num(x) + " " + num(py) + "V" + num(py + ph);
    ticks += "M" + num(x) + " " + num(py + ph) + "v5";
  }
  for (double t : yv.ticks) {
    double y = Y(t);
    if (s.grid) grid += "M" + num(px) + " " + num(y) + "H" + num(px + pw);
    ticks += "M" + num(px) + " " + num(y) + "h-5";
  }
  for (double t : xv.minor) ticks += "M" + num(X(t)) + " " + num(py + ph) + "v3";
  for (double t : yv.minor) ticks += "M" + num(px) + " " + num(Y(t)) + "h-3";
  if (!grid.empty())
    out += "<path d=\"" + grid + "\" stroke=\"#e5e5e5\" stroke-width=\"1\" fill=\"none\"/>\n";

  // Artists, clipped to the plot area.
  std::vector<LegendEntry> legend;
  out += "<g clip-path=\"url(#" + id + ")\">\n";
  for (const Artist& a : s.artists) {
    if (auto* l = std::get_if<LineArtist>(&a)) {
      std::string d;
      bool pen = false;
      for (std::size_t i = 0; i < l->x.size(); ++i) {
        double x = l->x[i], y = l->y[i];
        if (!ok(x, y)) {
          pen = false;  // a gap: the next point starts a new subpath
          continue;
        }
        if (!pen) {
          d += "M" + num(X(x)) + " " + num(Y(y));
        } else if (l->kind == LineKind::kStepPost) {
          d += "H" + num(X(x)) + "V" + num(Y(y));
        } else if (l->kind == LineKind::kStepPre) {
          d += "V" + num(Y(y)) + "H" + num(X(x));
        } else {
          d += "L" + num(X(x)) + " " + num(Y(y));
        }
        pen = true;
      }
      if (!d.empty()) out += "<path d=\"" + d + "\"" + stroke_attrs(l->style, l->color) + "/>\n";
      if (!l->style.label.empty()) legend.push_back(legend_entry(l->style, l->color));
    } else if (auto* p = std::get_if<ScatterArtist>(&a)) {
      bool stroked = stroked_marker(p->style.marker);
      out +=
          "<g" + std::string(stroked ? " fill=\"none\" stroke=\"" + p->color.hex() + "\" stroke-width=\"1.5\""
                                     : " fill=\"" + p->color.hex() + "\" stroke=\"none\"");
      if (p->style.opacity < 1) out += " opacity=\"" + num(p->style.opacity) + "\"";
      out += ">";
      for (std::size_t i = 0; i < p->x.size(); ++i)
        if (ok(p->x[i], p->y[i])) out += marker_svg(p->style.marker, X(p->x[i]), Y(p->y[i]), p->style.size);
      out += "</g>\n";
      if (!p->style.label.empty()) legend.push_back(legend_entry(p->style, p->color));
    } else if (auto* b = std::get_if<BandArtist>(&a)) {
      // One closed polygon per run of finite samples: upper edge forwards, lower edge back.
      std::string d;
      std::size_t i = 0, n = b->x.size();
      while (i < n) {
        while (i < n && !(ok(b->x[i], b->lo[i]) && ok(b->x[i], b->hi[i]))) ++i;
        std::size_t j = i;
        while (j < n && ok(b->x[j], b->lo[j]) && ok(b->x[j], b->hi[j])) ++j;
        if (j > i) {
          for (std::size_t k = i; k < j; ++k)
            d += (k == i ? "M" : "L") + num(X(b->x[k])) + " " + num(Y(b->hi[k]));
          for (std::size_t k = j; k-- > i;) d += "L" + num(X(b->x[k])) + " " + num(Y(b->lo[k]));
          d += "Z";
        }
        i = j;
      }
      if (!d.empty()) out += "<path d=\"" + d + "\"" + fill_attrs(b->style, b->color) + "/>\n";
      if (!b->style.label.empty()) legend.push_back(legend_entry(b->style, b->color));
    } else if (auto* h = std::get_if<BarsArtist>(&a)) {
      out += "<g" + fill_attrs(h->style, h->color) + ">";
      double base = s.yscale == Scale::kLog ? py + ph : Y(0.0);
      for (std::size_t i = 0; i < h->heights.size(); ++i) {
        double x0 = h->edges[i], x1 = h->edges[i + 1], v = h->heights[i];
        if (!ok(x0, v) || !ok(x1, v) || (s.yscale == Scale::kLog && v <= 0)) continue;
        double a0 = X(std::min(x0, x1)), a1 = X(std::max(x0, x1)), top_y = Y(v);
        out += "<rect x=\"" + num(a0) + "\" y=\"" + num(std::min(top_y, base)) + "\" width=\"" +
               num(a1 - a0) + "\" height=\"" + num(std::abs(base - top_y)) + "\"/>";
      }
      out += "</g>\n";
      if (!h->style.label.empty()) legend.push_back(legend_entry(h->style, h->color));
    } else if (auto* r = std::get_if<RefLineArtist>(&a)) {
      if (!finite(r->value)) continue;
      std::string d = r->horizontal ? "M" + num(px) + " " + num(Y(r->value)) + "H" + num(px + pw)
                                    : "M" + num(X(r->value)) + " " + num(py) + "V" + num(py + ph);
      out += "<path d=\"" + d + "\"" + stroke_attrs(r->style, r->color) + "/>\n";
      if (!r->style.label.empty()) legend.push_back(legend_entry(r->style, r->color));
    } else if (auto* g = std::get_if<PolygonArtist>(&a)) {
      std::string d;
      for (std::size_t i = 0; i < g->x.size(); ++i)
        if (ok(g->x[i], g->y[i])) d += (d.empty() ? "M" : "L") + num(X(g->x[i])) + " " + num(Y(g->y[i]));
      if (!d.empty()) out += "<path d=\"" + d + "Z\"" + fill_attrs(g->style, g->color) + "/>\n";
      if (!g->style.label.empty()) legend.push_back(legend_entry(g->style, g->color));
    } else if (auto* m = std::get_if<HeatmapArtist>(&a)) {
      // crispEdges: no hairline seams between neighbouring cells.
      out += "<g shape-rendering=\"crispEdges\" stroke=\"none\">";
      std::size_t nx = m->xe.size() - 1, ny = m->ye.size() - 1;
      for (std::size_t j = 0; j < ny; ++j)
        for (std::size_t i = 0; i < nx; ++i) {
          double v = m->values[j * nx + i];
          if (!finite(v) || !ok(m->xe[i], m->ye[j]) || !ok(m->xe[i + 1], m->ye[j + 1])) continue;
          double a0 = X(m->xe[i]), a1 = X(m->xe[i + 1]), b0 = Y(m->ye[j]), b1 = Y(m->ye[j + 1]);
          out += "<rect x=\"" + num(std::min(a0, a1)) + "\" y=\"" + num(std::min(b0, b1)) + "\" width=\"" +
                 num(std::abs(a1 - a0)) + "\" height=\"" + num(std::abs(b1 - b0)) + "\" fill=\"" +
                 viridis((v - m->vmin) / (m->vmax - m->vmin)).hex() + "\"/>";
        }
      out += "</g>\n";
    }
  }
  out += "</g>\n";

  // Text annotations are not clipped: a label may sit just outside the data.
  for (const Artist& a : s.artists) {
    auto* t = std::get_if<TextArtist>(&a);
    if (!t) continue;
    double x, y;
    if (t->style.axes_fraction) {
      x = px + t->x * pw, y = py + ph - t->y * ph;
    } else {
      if (!ok(t->x, t->y)) continue;
      x = X(t->x), y = Y(t->y);
    }
    if (!finite(x) || !finite(y)) continue;
    out += text_svg(x, y, xml_escape(t->text), t->style.size, anchor_name(t->style.anchor),
                    t->style.color == Color{0, 0, 0} ? "" : " fill=\"" + t->style.color.hex() + "\"");
  }

  // Frame, ticks and tick labels.
  out += "<rect x=\"" + num(px) + "\" y=\"" + num(py) + "\" width=\"" + num(pw) + "\" height=\"" + num(ph) +
         "\" fill=\"none\" stroke=\"#333333\" stroke-width=\"1\"/>\n";
  if (!ticks.empty())
    out += "<path d=\"" + ticks + "\" stroke=\"#333333\" stroke-width=\"1\" fill=\"none\"/>\n";
  for (std::size_t i = 0; i < xv.ticks.size(); ++i)
    out += text_svg(X(xv.ticks[i]), py + ph + 8 + tick_fs, label_svg(xv.labels[i]), tick_fs, "middle");
  for (std::size_t i = 0; i < yv.ticks.size(); ++i)
    out += text_svg(px - 8, Y(yv.ticks[i]) + tick_fs * 0.35, label_svg(yv.labels[i]), tick_fs, "end");
  if (!s.title.empty())
    out += text_svg(px + pw / 2, py - 8, xml_escape(s.title), title_fs, "middle", " font-weight=\"bold\"");
  if (!s.xlabel.empty())
    out +=
        text_svg(px + pw / 2, py + ph + 8 + tick_fs + 6 + label_fs, xml_escape(s.xlabel), label_fs, "middle");
  if (!s.ylabel.empty()) {
    double lx = cx + 8 + label_fs, ly = py + ph / 2;
    out += text_svg(lx, ly, xml_escape(s.ylabel), label_fs, "middle",
                    " transform=\"rotate(-90 " + num(lx) + " " + num(ly) + ")\"");
  }

  // Colour scale bar: stacked cells of the colour map, with its own ticks.
  if (colorbar) {
    double bx = px + pw + 14, bw = 14, steps = 64;
    out += "<g shape-rendering=\"crispEdges\" stroke=\"none\">";
    for (int k = 0; k < steps; ++k) {
      double y0 = py + ph - (k + 1) * ph / steps;
      out += "<rect x=\"" + num(bx) + "\" y=\"" + num(y0) + "\" width=\"" + num(bw) + "\" height=\"" +
             num(ph / steps + 0.5) + "\" fill=\"" + viridis((k + 0.5) / steps).hex() + "\"/>";
    }
    out += "</g>\n<rect x=\"" + num(bx) + "\" y=\"" + num(py) + "\" width=\"" + num(bw) + "\" height=\"" +
           num(ph) + "\" fill=\"none\" stroke=\"#333333\"/>\n";
    AxisView cv;
    cv.lo = colorbar->vmin, cv.hi = colorbar->vmax;
    fill_ticks(cv, 5);
    double max_w = 0;
    for (std::size_t i = 0; i < cv.ticks.size(); ++i) {
      double y = py + ph - (cv.ticks[i] - cv.lo) / (cv.hi - cv.lo) * ph;
      out += "<path d=\"M" + num(bx + bw) + " " + num(y) + "h4\" stroke=\"#333333\"/>\n";
      out += text_svg(bx + bw + 6, y + tick_fs * 0.35, xml_escape(cv.labels[i]), tick_fs, "start");
      max_w = std::max(max_w, text_width(cv.labels[i], tick_fs));
    }
    if (!colorbar->style.colorbar_label.empty()) {
      double lx = bx + bw + 10 + max_w + label_fs, ly = py + ph / 2;
      out += text_svg(lx, ly, xml_escape(colorbar->style.colorbar_label), label_fs, "middle",
                      " transform=\"rotate(-90 " + num(lx) + " " + num(ly) + ")\"");
    }
  }

  // Legend, in a corner of the plot area.
  if (s.legend != Legend::kNone && !legend.empty()) {
    const double row = 17, swatch = 22, pad = 6, fs = 11;
    double w = 0;
    for (const auto& e : legend) w = std::max(w, text_width(e.label, fs));
    w += swatch + 3 * pad;
    double h = legend.size() * row + pad;
    bool is_left = s.legend == Legend::kUpperLeft || s.legend == Legend::kLowerLeft;
    bool is_top = s.legend == Legend::kUpperLeft || s.legend == Legend::kUpperRight;
    double lx = is_left ? px + 8 : px + pw - 8 - w, ly = is_top ? py + 8 : py + ph - 8 - h;
    out += "<g class=\"legend\">\n<rect x=\"" + num(lx) + "\" y=\"" + num(ly) + "\" width=\"" + num(w) +
           "\" height=\"" + num(h) + "\" fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#bbbbbb\"/>\n";
    for (std::size_t i = 0; i < legend.size(); ++i) {
      const LegendEntry& e = legend[i];
      double yc = ly + pad + row * i + row / 2 - 2, sx = lx + pad;
      if (e.kind == LegendEntry::kLine) {
        out += "<path d=\"M" + num(sx) + " " + num(yc) + "h" + num(swatch) + "\"" +
               stroke_attrs(e.line, e.color) + "/>\n";
      } else if (e.kind == LegendEntry::kMarker) {
        bool stroked = stroked_marker(e.marker.marker);
        out += "<g" +
               std::string(stroked ? " fill=\"none\" stroke=\"" + e.color.hex() + "\" stroke-width=\"1.5\""
                                   : " fill=\"" + e.color.hex() + "\"") +
               ">" + marker_svg(e.marker.marker, sx + swatch / 2, yc, e.marker.size) + "</g>\n";
      } else {
        out += "<rect x=\"" + num(sx) + "\" y=\"" + num(yc - 5) + "\" width=\"" + num(swatch) +
               "\" height=\"10\"" + fill_attrs(e.fill, e.color) + "/>\n";
      }
      out += text_svg(sx + swatch + pad, yc + fs * 0.35, xml_escape(e.label), fs, "start");
    }
    out += "</g>\n";
  }
  out += "</g>\n";
}

// FNV-1a, for content-derived element ids.
std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace

// ---------------------------------------------------------------------------------------------- figure

Figure::Figure(int rows, int cols, double width_px, double height_px) : rows_(rows), cols_(cols) {
  if (rows < 1 || cols < 1) throw std::invalid_argument("plot: a figure needs at least one row and column");
  width_ = width_px > 0 ? width_px : 480.0 * cols;
  height_ = height_px > 0 ? height_px : 360.0 * rows;
  axes_.resize(static_cast<std::size_t>(rows * cols));
}

Axes& Figure::axes(int row, int col) {
  if (row < 0 || row >= rows_ || col < 0 || col >= cols_)
    throw std::out_of_range("plot: no axes (" + std::to_string(row) + ", " + std::to_string(col) + ") in a " +
                            std::to_string(rows_) + " x " + std::to_string(cols_) + " figure");
  return axes_[static_cast<std::size_t>(row * cols_ + col)];
}

Figure& Figure::title(std::string text) {
  title_ = std::move(text);
  return *this;
}

std::string Figure::to_svg() const {
  // Ids are written with a placeholder, then made unique to this figure's content: two figures inlined in one
  // HTML page must not share clip-path ids, and identical figures sharing them is harmless.
  const std::string placeholder = "@ID@";
  std::string body;
  double top = title_.empty() ? 0 : 30;
  double cw = width_ / cols_, ch = (height_ - top) / rows_;
  if (!title_.empty())
    body += text_svg(width_ / 2, 21, xml_escape(title_), 15, "middle", " font-weight=\"bold\"");
  for (int r = 0; r < rows_; ++r)
    for (int c = 0; c < cols_; ++c)
      render_axes(*axes_[static_cast<std::size_t>(r * cols_ + c)].s_, c * cw, top + r * ch, cw, ch,
                  placeholder + "-c" + std::to_string(r * cols_ + c), body);
  char prefix[24];
  std::snprintf(prefix, sizeof prefix, "fig%016llx", static_cast<unsigned long long>(fnv1a(body)));
  for (std::size_t pos = body.find(placeholder); pos != std::string::npos; pos = body.find(placeholder, pos))
    body.replace(pos, placeholder.size(), prefix);

  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" + num(width_) +
                    "\" height=\"" + num(height_) + "\" viewBox=\"0 0 " + num(width_) + " " + num(height_) +
                    "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n";
  if (!title_.empty()) svg += "<title>" + xml_escape(title_) + "</title>\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  return svg + body + "</svg>\n";
}

void Figure::save(const std::string& path) const {
  std::string svg = to_svg();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot create");
  out << svg;
  out.flush();
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace flume::plot
