// The top-down geometry the report draws the debris on: the harbour apron behind the quay wall and the
// obstacle columns. Built from the campaign's parameters and scene values, not from solver internals; the
// defaults are the Waseda basin of Goseberg et al. (2016b): quay wall at x = 4.45 m, apron to the back wall
// at x = 9.0 m, basin 4 m wide; obstacles are 0.10 m square columns 0.325 m apart across, rows 0.45 m apart
// from x = 5.11 m (upstream face), centred across the basin; layouts 0x0, 5x1, 5x2.
#pragma once
#include <string>
#include <vector>

#include "report/campaign_data.h"

namespace flume::report {

struct Rect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct ApronGeometry {
  double quay_x_m = 4.45;
  double end_x_m = 9.0;
  double y_lo_m = 0.0, y_hi_m = 4.0;
  std::string layout = "0x0";  // columns x rows
  std::string layout_source;   // "overrides", "scene", "parameter", or "default"
  std::vector<Rect> obstacles;
};

// The obstacle rectangles of a layout "CxR" (C columns across, R rows), centred across at y_mid; throws
// std::invalid_argument for another form.
std::vector<Rect> obstacle_layout(const std::string& layout, double y_mid = 2.0);

// Layout from a fixed value (overrides or scene) of `obstacles.layout`; when that path is a sampled
// parameter, each run's own value (`row`); otherwise 0x0 with source "default". The basin's width from a
// fixed `basin.width_m` (a reduced strip such as scenes/waseda/waseda_strip.json), else 4 m.
ApronGeometry apron_geometry(const CampaignData& data, const RunRow* row = nullptr);

}  // namespace flume::report
