#include "solver/debris_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace flume {
namespace {

constexpr double kDeg = 180.0 / M_PI;

double norm3(const std::array<double, 3>& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// Distance from point p to the axis-aligned box [lo, hi] (0 inside).
double point_box_distance(const Eigen::Vector3d& p, const Vec3d& lo, const Vec3d& hi) {
  double s = 0;
  for (int a = 0; a < 3; ++a) {
    const double q = std::max({lo[a] - p[a], p[a] - hi[a], 0.0});
    s += q * q;
  }
  return std::sqrt(s);
}

// Gap between a debris box (centre, orientation, size) and an axis-aligned column: the smaller of the
// distances from the debris' corners and edge midpoints to the column and from the column's vertical edges
// (sampled) to the debris. Exact enough for "touching or not" at a millimetre scale.
double debris_column_gap(const Eigen::Vector3d& c, const Eigen::Quaterniond& q, const Vec3d& size, const Vec3d& lo,
                         const Vec3d& hi) {
  const Eigen::Matrix3d R = q.toRotationMatrix();
  double gap = 1e300;
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        const Eigen::Vector3d local(0.5 * i * size[0], 0.5 * j * size[1], 0.5 * k * size[2]);
        gap = std::min(gap, point_box_distance(c + R * local, lo, hi));
      }
  RigidBoxView v{};
  for (int a = 0; a < 3; ++a) {
    v.centre[a] = c[a];
    v.half_extent[a] = 0.5 * size[a];
    for (int b = 0; b < 3; ++b) v.rotation[a * 3 + b] = R(a, b);
  }
  for (int ex = 0; ex < 2; ++ex)
    for (int ey = 0; ey < 2; ++ey)
      for (int s = 0; s <= 20; ++s) {
        const double p[3] = {ex ? hi[0] : lo[0], ey ? hi[1] : lo[1], c[2] - 0.5 * size[2] + size[2] * s / 20.0};
        gap = std::min(gap, std::max(0.0, box_signed_distance(v, p)));
      }
  return gap;
}

}  // namespace

std::map<std::string, double> debris_metrics(const Scene& scene, const DebrisRecorder& recorder, double dam_gap_m) {
  std::map<std::string, double> m;
  int mobilised = 0, dammed = 0, at_rest = 0;
  const double v_rest = scene.debris.rest_speed_m_s, hold = scene.debris.rest_hold_s;
  for (int b = 0; b < recorder.body_count(); ++b) {
    const std::string k = recorder.name(b) + ".";
    const DebrisSeries& s = recorder.solver_rate(b);
    const DebrisSeries& r = recorder.resampled(b);
    if (s.size() == 0) continue;
    const auto& p0 = s.position.front();
    size_t runup = 0;
    for (size_t i = 1; i < s.size(); ++i)
      if (s.position[i][0] > s.position[runup][0]) runup = i;
    const auto& pr = s.position[runup];
    const auto& pe = s.position.back();
    const double lon_max = pr[0] - p0[0], lat_run = pr[1] - p0[1];
    const double lon_rest = pe[0] - p0[0], lat_rest = pe[1] - p0[1];
    m[k + "initial_x_m"] = p0[0];
    m[k + "initial_y_m"] = p0[1];
    m[k + "runup_x_m"] = pr[0];
    m[k + "runup_y_m"] = pr[1];
    m[k + "runup_time_s"] = s.time[runup];
    m[k + "rest_x_m"] = pe[0];
    m[k + "rest_y_m"] = pe[1];
    m[k + "longitudinal_max_m"] = lon_max;
    m[k + "longitudinal_rest_m"] = lon_rest;
    m[k + "lateral_runup_m"] = lat_run;
    m[k + "lateral_rest_m"] = lat_rest;
    m[k + "spreading_runup_deg"] = std::atan2(lat_run, lon_max) * kDeg;
    m[k + "spreading_rest_deg"] = std::atan2(lat_rest, lon_rest) * kDeg;
    const double v_end = norm3(s.velocity.back());
    m[k + "final_speed_m_s"] = v_end;
    // At rest: slower than v_rest from moving_until on, for at least `hold` before the record ends. A debris
    // never faster than v_rest has moving_until at the record's start.
    double moving_until = s.time.front();
    for (size_t i = 0; i < s.size(); ++i)
      if (norm3(s.velocity[i]) > v_rest) moving_until = s.time[i];
    const bool rest = v_end <= v_rest && s.time.back() - moving_until >= hold;  // v_end: for hold = 0
    m[k + "moving_until_s"] = moving_until;
    m[k + "at_rest"] = rest ? 1.0 : 0.0;
    at_rest += rest;
    double peak = 0, peak30 = 0;
    for (const auto& f : s.force) peak = std::max(peak, norm3(f));
    for (const auto& f : r.force) peak30 = std::max(peak30, norm3(f));
    m[k + "accel_peak_force_n"] = peak;
    m[k + "accel_peak_force_30hz_n"] = peak30;
    // Dammed: resting against an obstacle column at the end.
    const DebrisBody* spec = nullptr;
    for (const auto& d : scene.debris.bodies)
      if (d.name == recorder.name(b)) spec = &d;
    bool dam = false;
    if (spec) {
      const auto& qe = s.orientation.back();
      const Eigen::Quaterniond q(qe[0], qe[1], qe[2], qe[3]);
      const Eigen::Vector3d c(pe[0], pe[1], pe[2]);
      for (const auto& box : scene.basin.obstacle_boxes)
        dam |= debris_column_gap(c, q, spec->size, box[0], box[1]) <= dam_gap_m;
      if (lon_max > 0.5 * spec->size[0]) ++mobilised;
    }
    m[k + "dammed"] = dam ? 1.0 : 0.0;
    dammed += dam;
  }
  m["debris.mobilised_count"] = mobilised;
  m["debris.at_rest_count"] = at_rest;
  (void)dammed;  // the report derives debris.dammed_count from the per-debris flags
  return m;
}

}  // namespace flume
