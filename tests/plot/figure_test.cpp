#include "common/plot/figure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "tests/plot/xml_check.h"

namespace fs = std::filesystem;
using namespace flume::plot;
using flume::plot::test::check_xml;
using flume::plot::test::Element;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<const Element*> find_all(const std::vector<Element>& els, const std::string& name) {
  std::vector<const Element*> out;
  for (const auto& e : els)
    if (e.name == name) out.push_back(&e);
  return out;
}

int count_of(const std::string& s, char c) {
  int n = 0;
  for (char x : s) n += x == c;
  return n;
}

// The checker itself must reject what it claims to (otherwise every test below passes vacuously).
TEST(XmlCheck, RejectsMalformedInput) {
  EXPECT_TRUE(check_xml("<a x=\"1\"><b/>t &amp; &#x41;</a>").error.empty());
  EXPECT_FALSE(check_xml("<a><b></a></b>").error.empty());
  EXPECT_FALSE(check_xml("<a>x & y</a>").error.empty());
  EXPECT_FALSE(check_xml("<a t=\"<\"/>").error.empty());
  EXPECT_FALSE(check_xml("<a></a><b/>").error.empty());
  EXPECT_FALSE(check_xml("<a>").error.empty());
  EXPECT_FALSE(check_xml("<a x=\"1\" x=\"2\"/>").error.empty());
  EXPECT_FALSE(check_xml("<a>\x01</a>").error.empty());
}

bool is_nice_step(double step) {
  double mag = std::pow(10.0, std::floor(std::log10(step) + 1e-12));
  double m = step / mag;
  for (double ok : {1.0, 2.0, 2.5, 5.0})
    if (std::abs(m - ok) < 1e-9) return true;
  return false;
}

TEST(Ticks, NiceNumbersCoveringTheData) {
  struct Case {
    double lo, hi;
  };
  for (Case c : {Case{0, 1}, Case{0.013, 0.987}, Case{-3.7, 12.2}, Case{101.3, 101.9}, Case{-1e-6, 3e-6},
                 Case{0, 7.3e5}, Case{5, 5}, Case{0, 0}, Case{-250, -3}}) {
    NiceAxis axis = nice_axis(c.lo, c.hi);
    double lo = axis.lo, hi = axis.hi;
    EXPECT_LE(lo, c.lo) << c.lo << " " << c.hi;
    EXPECT_GE(hi, c.hi) << c.lo << " " << c.hi;
    EXPECT_LT(lo, hi);
    const std::vector<double>& t = axis.ticks;
    ASSERT_GE(t.size(), 3u) << c.lo << " " << c.hi;
    EXPECT_LE(t.size(), 11u);
    double step = t[1] - t[0];
    EXPECT_TRUE(is_nice_step(step)) << step;
    // The widened limits are themselves ticks, so the ticks span the data.
    EXPECT_NEAR(t.front(), lo, step * 1e-6);
    EXPECT_NEAR(t.back(), hi, step * 1e-6);
    for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], step, step * 1e-6);
    for (double v : t) EXPECT_NEAR(v / step, std::round(v / step), 1e-6);
  }
  EXPECT_EQ(nice_ticks(0, 1), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  // Not widened further than one step beyond the data on either side.
  NiceAxis a = nice_axis(-1.2, 1.2);
  EXPECT_EQ(a.ticks, (std::vector<double>{-1.5, -1, -0.5, 0, 0.5, 1, 1.5}));
  EXPECT_EQ(nice_ticks(-10, 10, 4), (std::vector<double>{-10, -5, 0, 5, 10}));
}

TEST(Ticks, LogTicksAreDecades) {
  EXPECT_EQ(log_ticks(1e-3, 10), (std::vector<double>{1e-3, 1e-2, 1e-1, 1, 10}));
  std::vector<double> narrow = log_ticks(1, 10);
  EXPECT_EQ(narrow, (std::vector<double>{1, 2, 5, 10}));
  EXPECT_LE(log_ticks(1e-20, 1e20).size(), 12u);
  EXPECT_THROW(log_ticks(0, 10), std::invalid_argument);
}

TEST(Figure, LogAxisRefusesNonPositiveData) {
  Figure fig;
  fig.axes().title("spectrum").line({1, 2, 3}, {1.0, 0.0, 2.0}).yscale(Scale::kLog);
  try {
    fig.to_svg();
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("log y axis"), std::string::npos) << what;
    EXPECT_NE(what.find("spectrum"), std::string::npos) << what;
  }
  Figure fx;
  fx.axes().xscale(Scale::kLog).scatter({-1, 2}, {1, 2});
  EXPECT_THROW(fx.to_svg(), std::invalid_argument);
  // Positive data on log axes draws, with 10^k labels.
  Figure ok;
  ok.axes().xscale(Scale::kLog).yscale(Scale::kLog).line({1e-2, 1, 1e3}, {1, 10, 1e4});
  std::string svg = ok.to_svg();
  EXPECT_TRUE(check_xml(svg).error.empty()) << check_xml(svg).error;
  EXPECT_NE(svg.find(">10<tspan"), std::string::npos);
}

TEST(Figure, NaNBreaksLinesIntoSubpaths) {
  Figure fig;
  fig.axes().line({0, 1, 2, 3, 4, 5}, {0, 1, kNaN, 3, 4, 5}, {});
  fig.axes().band({0, 1, 2, 3}, {0, kNaN, 0, 0}, {1, 1, 1, 1}, {});
  fig.axes().scatter({0, kNaN, 2}, {1, 1, std::numeric_limits<double>::infinity()}, {});
  std::string svg = fig.to_svg();
  auto xml = check_xml(svg);
  ASSERT_TRUE(xml.error.empty()) << xml.error;
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
  std::vector<std::string> data_paths;
  for (const Element* p : find_all(xml.elements, "path"))
    if (p->attrs.count("stroke") && p->attrs.at("stroke") == palette(0).hex())
      data_paths.push_back(p->attrs.at("d"));
  ASSERT_EQ(data_paths.size(), 1u);
  EXPECT_EQ(count_of(data_paths[0], 'M'), 2);  // [0, 1] and [3, 5]
  EXPECT_EQ(count_of(data_paths[0], 'L'), 3);
  // The band splits into [0] (a single sample, still a closed path) and [2, 3].
  std::string band;
  for (const Element* p : find_all(xml.elements, "path"))
    if (p->attrs.count("fill") && p->attrs.at("fill") == palette(1).hex()) band = p->attrs.at("d");
  EXPECT_EQ(count_of(band, 'M'), 2);
  EXPECT_EQ(count_of(band, 'Z'), 2);
  // Only the one finite scatter point is drawn.
  EXPECT_EQ(find_all(xml.elements, "circle").size(), 1u);
}

TEST(Figure, TextIsEscaped) {
  Figure fig;
  fig.title("Run <7> & \"friends\"");
  fig.axes()
      .title("a < b")
      .xlabel("x & y")
      .ylabel("'quoted'")
      .line({0, 1}, {0, 1}, LineStyle{std::nullopt, 1.5, Dash::kSolid, 1.0, "</svg><script>"})
      .legend(Legend::kUpperLeft)
      .text(0.5, 0.5, "bell\x07 and bad utf8 \xff\xfe ok \xc3\xa9");
  std::string svg = fig.to_svg();
  auto xml = check_xml(svg);
  ASSERT_TRUE(xml.error.empty()) << xml.error;
  EXPECT_NE(svg.find("Run &lt;7&gt; &amp; &quot;friends&quot;"), std::string::npos);
  EXPECT_NE(svg.find("&lt;/svg&gt;&lt;script&gt;"), std::string::npos);
  EXPECT_EQ(svg.find("<script"), std::string::npos);
  EXPECT_NE(svg.find("ok \xc3\xa9"), std::string::npos);   // valid UTF-8 kept
  EXPECT_NE(svg.find("\xef\xbf\xbd"), std::string::npos);  // invalid bytes replaced
  EXPECT_EQ(svg.find('\x07'), std::string::npos);
  EXPECT_EQ(xml_escape("a&b<c>\"d'"), "a&amp;b&lt;c&gt;&quot;d&apos;");
}

TEST(Figure, EveryArtistInAGridIsWellFormed) {
  Figure fig(2, 2, 960, 720);
  fig.title("all artists");
  std::vector<double> t, m, lo, hi;
  for (int i = 0; i <= 50; ++i) {
    t.push_back(0.1 * i);
    m.push_back(std::sin(0.1 * i));
    lo.push_back(m.back() - 0.2);
    hi.push_back(m.back() + 0.2);
  }
  LineStyle dashed;
  dashed.dash = Dash::kDashed;
  dashed.label = "reference";
  FillStyle band_style;
  band_style.label = "band";
  fig.axes(0, 0)
      .title("series")
      .xlabel("t [s]")
      .ylabel("eta [m]")
      .band(t, lo, hi, band_style)
      .line(t, m)
      .step(t, m, {}, Step::kPre)
      .hline(0.5, dashed)
      .vline(2.0)
      .legend(Legend::kLowerRight);
  MarkerStyle tri;
  tri.marker = Marker::kTriangle;
  tri.label = "runs";
  fig.axes(0, 1)
      .scatter({1, 2, 3}, {3, 1, 2}, tri)
      .scatter({1, 2}, {2, 2}, MarkerStyle{std::nullopt, Marker::kCross, 5.0, 1.0, ""})
      .histogram({0.5, 1.5, 1.7, 2.2, 2.9}, 4)
      .legend(Legend::kUpperRight);
  std::vector<double> xe{0, 1, 2, 3}, ye{0, 1, 2}, v{0.0, 0.5, kNaN, 0.25, 1.0, 0.75};
  HeatmapStyle hs;
  hs.colorbar_label = "P(overtop)";
  fig.axes(1, 0)
      .title("map")
      .equal_aspect()
      .heatmap(xe, ye, v, hs)
      .rect(0.2, 0.2, 0.8, 0.6)
      .polygon({1, 2, 1.5}, {1, 1, 1.8})
      .text(0.05, 0.95, "note", TextStyle{9, Color{}, Anchor::kStart, true});
  fig.axes(1, 1).yscale(Scale::kLog).bars({0, 1, 2, 3}, {10, 0, 1000}).ylim(1, 1e4);
  std::string svg = fig.to_svg();
  auto xml = check_xml(svg);
  ASSERT_TRUE(xml.error.empty()) << xml.error;
  EXPECT_EQ(xml.elements.front().name, "svg");
  EXPECT_EQ(find_all(xml.elements, "clipPath").size(), 4u);
  // The heat map: 5 finite cells, the lowest value drawn in the low end of viridis, the highest at the top.
  int low = 0, high = 0;
  for (const Element* r : find_all(xml.elements, "rect")) {
    auto f = r->attrs.find("fill");
    if (f == r->attrs.end()) continue;
    low += f->second == viridis(0).hex();
    high += f->second == viridis(1).hex();
  }
  EXPECT_EQ(low, 1);
  EXPECT_EQ(high, 1);
  // Log bars: the empty bin is left out.
  EXPECT_NE(svg.find("P(overtop)"), std::string::npos);

  fs::path file = fs::temp_directory_path() / ("flume_plot_" + std::to_string(::getpid()) + ".svg");
  fig.save(file.string());
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), svg);
  fs::remove(file);
  EXPECT_THROW(fig.save("/nonexistent-dir/x.svg"), std::runtime_error);
}

TEST(Figure, EqualAspectGivesEqualUnitsPerPixel) {
  Figure fig(1, 1, 600, 600);
  fig.axes().equal_aspect().xlim(0, 10).ylim(0, 2).rect(1, 0.5, 3, 1.5);
  auto xml = check_xml(fig.to_svg());
  ASSERT_TRUE(xml.error.empty()) << xml.error;
  auto clips = find_all(xml.elements, "rect");
  const Element* clip = nullptr;
  for (std::size_t i = 0; i < xml.elements.size(); ++i)
    if (xml.elements[i].name == "clipPath") clip = &xml.elements[i + 1];
  ASSERT_NE(clip, nullptr);
  double w = std::stod(clip->attrs.at("width")), h = std::stod(clip->attrs.at("height"));
  EXPECT_NEAR(w / h, 5.0, 0.01);
}

TEST(Figure, IdsDifferBetweenFiguresAndPanelsAreChecked) {
  Figure a, b;
  a.axes().line({0, 1}, {0, 1});
  b.axes().line({0, 1}, {1, 0});
  auto id_of = [](const std::string& svg) {
    auto xml = check_xml(svg);
    return find_all(xml.elements, "clipPath").at(0)->attrs.at("id");
  };
  EXPECT_NE(id_of(a.to_svg()), id_of(b.to_svg()));
  EXPECT_EQ(a.to_svg(), a.to_svg());  // deterministic
  EXPECT_THROW(a.axes(1, 0), std::out_of_range);
  EXPECT_THROW(a.axes().line({0, 1}, {0}), std::invalid_argument);
  EXPECT_THROW(a.axes().bars({0, 1}, {1, 2}), std::invalid_argument);
  EXPECT_THROW(a.axes().heatmap({0, 1}, {0, 1}, {1, 2}), std::invalid_argument);
  EXPECT_THROW(a.axes().xlim(1, 1), std::invalid_argument);
}

TEST(Palette, ColourBlindSafeAndCycling) {
  EXPECT_EQ(palette(0).hex(), "#0072b2");
  EXPECT_EQ(palette(1).hex(), "#e69f00");
  EXPECT_EQ(palette(8), palette(0));
  EXPECT_EQ(viridis(0).hex(), "#440154");
  EXPECT_EQ(viridis(1).hex(), "#fde725");
  EXPECT_EQ(viridis(kNaN), viridis(0));
}

}  // namespace
