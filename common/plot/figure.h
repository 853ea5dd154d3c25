// Self-contained SVG figures: docs, validation plots, calibration fits, and the inline SVG of the HTML report
// (no fonts, scripts or links fetched: it renders in any browser offline).
//
//   flume::plot::Figure fig(1, 2);
//   auto& ax = fig.axes(0, 0).title("Gauge 3").xlabel("t [s]").ylabel("eta [m]");
//   ax.band(t, lo, hi, {.label = "90 % band"});   // C++20 designated initialisers shown for brevity
//   ax.line(t, mean, {.label = "mean"}).legend(flume::plot::Legend::kUpperRight);
//   fig.save("gauge3.svg");
//
// Data errors (size mismatch, non-positive data on a log axis) throw std::invalid_argument; the log check
// happens when the figure is drawn, so the scale may be set before or after the data.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace flume::plot {

struct Color {
  std::uint8_t r = 0, g = 0, b = 0;
  std::string hex() const;  // "#rrggbb"
  bool operator==(const Color& o) const { return r == o.r && g == o.g && b == o.b; }
};

// Okabe & Ito (2008) colour-blind-safe palette, in the order artists without a colour take them (cycles).
Color palette(std::size_t i);
// Viridis (perceptually uniform, readable with colour-vision deficiency) at t in [0, 1], for heat maps.
Color viridis(double t);

enum class Scale { kLinear, kLog };
enum class Dash { kSolid, kDashed, kDotted, kDashDot };
enum class Marker { kCircle, kSquare, kTriangle, kDiamond, kCross, kPlus };
enum class Legend { kNone, kUpperRight, kUpperLeft, kLowerLeft, kLowerRight };
enum class Anchor { kStart, kMiddle, kEnd };
enum class Step { kPre, kPost };  // where the jump is: at the start (pre) or the end (post) of each interval

// An empty `label` keeps an artist out of the legend; an unset `color` takes the axes' next palette colour
// (reference lines and shapes default to grey instead).
struct LineStyle {
  std::optional<Color> color;
  double width = 1.5;
  Dash dash = Dash::kSolid;
  double opacity = 1.0;
  std::string label;
};
struct MarkerStyle {
  std::optional<Color> color;
  Marker marker = Marker::kCircle;
  double size = 5.0;  // px, across
  double opacity = 1.0;
  std::string label;
};
struct FillStyle {
  std::optional<Color> color;
  double opacity = 0.35;
  std::optional<Color> edge;  // outline; none when unset
  double edge_width = 1.0;
  std::string label;
};
struct TextStyle {
  double size = 11.0;  // px
  Color color{0, 0, 0};
  Anchor anchor = Anchor::kStart;
  bool axes_fraction = false;  // x, y in [0, 1] of the plot area instead of data coordinates
};
struct HeatmapStyle {
  std::optional<double> vmin, vmax;  // colour scale limits; default the finite data range
  bool colorbar = true;
  std::string colorbar_label;
};

// "Nice" tick positions: multiples of {1, 2, 2.5, 5} x 10^k inside [lo, hi], about `target` of them.
std::vector<double> nice_ticks(double lo, double hi, int target = 5);
// Axis limits widened outwards to whole tick steps, and those ticks, so that they cover [data_lo, data_hi];
// a degenerate range is widened around its value. ticks.front() == lo and ticks.back() == hi.
struct NiceAxis {
  double lo = 0, hi = 1;
  std::vector<double> ticks;
};
NiceAxis nice_axis(double data_lo, double data_hi, int target = 5);
// Ticks of a log axis over [lo, hi] (both > 0): decades, with 2 and 5 added when there are under two decades.
std::vector<double> log_ticks(double lo, double hi);
// Escapes text for XML/HTML content and attribute values (& < > " '); drops characters XML 1.0 forbids and
// replaces invalid UTF-8 with U+FFFD, so any input yields well-formed output.
std::string xml_escape(std::string_view text);

class Axes {
 public:
  Axes();
  ~Axes();
  Axes(Axes&&) noexcept;
  Axes& operator=(Axes&&) noexcept;

  Axes& title(std::string text);
  Axes& xlabel(std::string text);
  Axes& ylabel(std::string text);
  Axes& xscale(Scale s);
  Axes& yscale(Scale s);
  Axes& xlim(double lo, double hi);  // fixed limits; data outside is clipped
  Axes& ylim(double lo, double hi);
  Axes& equal_aspect(bool on = true);  // one data unit is as long on both axes (top-down maps)
  Axes& legend(Legend where);
  Axes& grid(bool on);

  // NaN or infinite values break lines, bands and steps (a gap), and skip markers, bars and cells.
  Axes& line(const std::vector<double>& x, const std::vector<double>& y, const LineStyle& style = {});
  Axes& scatter(const std::vector<double>& x, const std::vector<double>& y, const MarkerStyle& style = {});
  Axes& step(const std::vector<double>& x, const std::vector<double>& y, const LineStyle& style = {},
             Step where = Step::kPost);
  Axes& band(const std::vector<double>& x, const std::vector<double>& lower, const std::vector<double>& upper,
             const FillStyle& style = {});
  // Bars over [edges[i], edges[i+1]] of height heights[i] (edges.size() == heights.size() + 1). On a log y
  // axis empty bars are left out and the others start at the bottom of the axis.
  Axes& bars(const std::vector<double>& edges, const std::vector<double>& heights,
             const FillStyle& style = {});
  // Equal-width bins over the finite range of `samples`; density=true scales the area to 1.
  Axes& histogram(const std::vector<double>& samples, int bins, const FillStyle& style = {},
                  bool density = false);
  Axes& hline(double y, const LineStyle& style = {});
  Axes& vline(double x, const LineStyle& style = {});
  Axes& rect(double x0, double y0, double x1, double y1, const FillStyle& style = {});
  Axes& polygon(const std::vector<double>& x, const std::vector<double>& y, const FillStyle& style = {});
  // Cells [x_edges[i], x_edges[i+1]] x [y_edges[j], y_edges[j+1]] coloured by values[j * nx + i] (row j is
  // a y interval), with a colour scale bar at the right. NaN cells are left empty.
  Axes& heatmap(const std::vector<double>& x_edges, const std::vector<double>& y_edges,
                const std::vector<double>& values, const HeatmapStyle& style = {});
  Axes& text(double x, double y, std::string text, const TextStyle& style = {});

  struct State;  // defined in figure.cpp

 private:
  friend class Figure;
  std::unique_ptr<State> s_;
};

class Figure {
 public:
  // A rows x cols grid of axes; size in px, by default 480 x 360 per panel.
  explicit Figure(int rows = 1, int cols = 1, double width_px = 0, double height_px = 0);
  Axes& axes(int row = 0, int col = 0);
  Figure& title(std::string text);

  // A complete <svg> element without an XML declaration, so it can be inlined in HTML as it is. Element ids
  // are derived from a hash of the content, so several figures can share one HTML page.
  std::string to_svg() const;
  // Writes to_svg() to `path`; throws std::runtime_error naming the file on failure.
  void save(const std::string& path) const;

 private:
  int rows_, cols_;
  double width_, height_;
  std::string title_;
  std::vector<Axes> axes_;
};

}  // namespace flume::plot
