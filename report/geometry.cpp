#include "report/geometry.h"

#include <cstdio>
#include <stdexcept>

namespace flume::report {

std::vector<Rect> obstacle_layout(const std::string& layout, double y_mid) {
  int columns = 0, rows = 0;
  char tail = 0;
  if (std::sscanf(layout.c_str(), "%dx%d%c", &columns, &rows, &tail) != 2 || columns < 0 || rows < 0 ||
      columns > 50 || rows > 20)
    throw std::invalid_argument("obstacles.layout: expected CxR such as 0x0, 5x1 or 5x2 (got '" + layout +
                                "')");
  const double side = 0.10, pitch = 0.325, row_dx = 0.45, x_first = 5.11;
  std::vector<Rect> out;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const double yc = y_mid + (c - (columns - 1) / 2.0) * pitch;
      const double x0 = x_first + r * row_dx;
      out.push_back({x0, yc - side / 2, x0 + side, yc + side / 2});
    }
  return out;
}

ApronGeometry apron_geometry(const CampaignData& data, const RunRow* row) {
  ApronGeometry g;
  const std::string path = "obstacles.layout";
  g.layout_source = "default";
  if (auto it = data.fixed.find(path); it != data.fixed.end() && it->second.is_text) {
    g.layout = it->second.text;
    g.layout_source = data.fixed_source.at(path);
  } else if (const int j = data.parameter_index(path); j >= 0 && row && row->params[j].is_text) {
    g.layout = row->params[j].text;
    g.layout_source = "parameter";
  }
  if (auto it = data.fixed.find("basin.width_m"); it != data.fixed.end() && !it->second.is_text &&
                                                   it->second.number > 0)
    g.y_hi_m = it->second.number;
  g.obstacles = obstacle_layout(g.layout, 0.5 * (g.y_lo_m + g.y_hi_m));
  return g;
}

}  // namespace flume::report
