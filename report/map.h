// The top-down apron map shared by the campaign report's debris section and `flume debris-paths`: the basin's
// last 0.6 m, the quay wall, the apron, the obstacle columns, and the guideline cones of the spreading angle.
#pragma once
#include <string>

#include "common/plot/figure.h"
#include "report/geometry.h"

namespace flume::report {

// Limits, labels, equal aspect, and the geometry drawn underneath whatever follows.
void draw_apron(plot::Axes& ax, const ApronGeometry& g);

// A spreading cone from the apex (the debris field's initial centroid) downstream to x_end, half-angle `deg`:
// Naito et al. (2014) 22.5 deg, or Nistor et al. (2017) eq. 59.
void draw_cone(plot::Axes& ax, double apex_x, double apex_y, double x_end, double deg, const plot::Color& color,
               plot::Dash dash, const std::string& label);

}  // namespace flume::report
