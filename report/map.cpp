#include "report/map.h"

#include <cmath>

namespace flume::report {

void draw_apron(plot::Axes& ax, const ApronGeometry& g) {
  ax.equal_aspect()
      .xlim(g.quay_x_m - 0.6, g.end_x_m)
      .ylim(g.y_lo_m, g.y_hi_m)
      .xlabel("x downstream [m]")
      .ylabel("y across [m]");
  ax.rect(g.quay_x_m - 0.6, g.y_lo_m, g.quay_x_m, g.y_hi_m,
          {.color = plot::Color{86, 180, 233}, .opacity = 0.15});
  ax.rect(g.quay_x_m, g.y_lo_m, g.end_x_m, g.y_hi_m, {.color = plot::Color{200, 200, 200}, .opacity = 0.25});
  ax.vline(g.quay_x_m, {.color = plot::Color{60, 60, 60}, .width = 2.0});
  for (const auto& o : g.obstacles)
    ax.rect(o.x0, o.y0, o.x1, o.y1, {.color = plot::Color{40, 40, 40}, .opacity = 0.9});
}

void draw_cone(plot::Axes& ax, double apex_x, double apex_y, double x_end, double deg, const plot::Color& color,
               plot::Dash dash, const std::string& label) {
  const double L = x_end - apex_x, t = std::tan(deg * M_PI / 180.0);
  ax.polygon({apex_x, x_end, x_end}, {apex_y, apex_y - L * t, apex_y + L * t}, {.color = color, .opacity = 0.06});
  ax.line({x_end, apex_x, x_end}, {apex_y - L * t, apex_y, apex_y + L * t},
          {.color = color, .width = 1.5, .dash = dash, .label = label});
}

}  // namespace flume::report
