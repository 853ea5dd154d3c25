// Small pieces the report's HTML sections share (html.cpp, surrogates.cpp): number formatting, an estimate
// with its interval, a figure or the note that replaces it, a proportional bar, the palette.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/plot/figure.h"
#include "report/statistics.h"

namespace flume::report::html {

inline std::string fmt(double v, int digits = 4) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

inline std::string est(const Estimate& e, int digits = 4) {
  return fmt(e.value, digits) + " <span class=ci>[" + fmt(e.ci.lo, digits) + ", " + fmt(e.ci.hi, digits) +
         "]</span>";
}

inline std::string pct(double conf) { return fmt(conf * 100, 3) + " %"; }

inline const plot::Color kBlue = plot::palette(0), kOrange = plot::palette(1), kGreen = plot::palette(2),
                         kVermillion = plot::palette(3), kPurple = plot::palette(4), kGrey{120, 120, 120};

// A figure that cannot be drawn (bad data) becomes a note instead of ending the report.
inline std::string svg_or_note(const plot::Figure& fig) {
  try {
    return fig.to_svg();
  } catch (const std::exception& e) {
    return "<p class=note>figure not drawn: " + plot::xml_escape(e.what()) + "</p>";
  }
}

inline std::string bar(double v, const plot::Color& c) {
  const double w = std::clamp(std::isfinite(v) ? std::abs(v) : 0.0, 0.0, 1.0) * 100;
  return "<span class=bar style=\"width:" + fmt(w, 3) + "px;background:" + c.hex() + "\"></span>";
}

}  // namespace flume::report::html
