// Instruments: free-surface gauges, velocity probes, load cells, pressure probes and diagnostics, sampled at their rates.
// Templated on the solver so they read its particle arrays directly, in its own precision.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "solver/bspline_weight.h"
#include "solver/checkpoint.h"
#include "solver/connected_depth.h"
#include "solver/particle_sums.h"
#include "solver/pressure_probes.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "solver/solids.h"

namespace flume {

// Top of the solid under a horizontal position: the highest box top or upward-facing plane over it, or the
// domain floor. A dry gauge reads this level, as a real gauge on a dry apron reads the apron.
inline double ground_level(const Scene& s, const Vec3d& p) {
  const int up = s.dimension - 1;
  double z = s.domain_lo[up];
  for (const auto& b : s.boundaries) {
    const auto& sh = b.shape;
    if (sh.type == ShapeType::kBox) {
      bool over = true;
      for (int d = 0; d < up; ++d) over &= p[d] >= sh.lo[d] && p[d] <= sh.hi[d];
      if (over) z = std::max(z, sh.hi[up]);
    } else if (sh.normal[up] > 0.5) {  // a floor-like plane
      double h = sh.point[up];
      for (int d = 0; d < up; ++d) h -= (p[d] - sh.point[d]) * sh.normal[d] / sh.normal[up];
      z = std::max(z, h);
    }
  }
  return z;
}

// A gauge's image across a symmetry plane that its footprint (1.5 cells) reaches: the half-width scene's gauge
// then also counts the water's mirror image (the particles summed at the image position), and reads as the
// whole basin's gauge does. False when no plane is within reach.
inline bool gauge_image(const Scene& s, const Vec3d& position, Vec3d& image) {
  for (const auto& b : s.boundaries) {
    if (b.condition != BoundaryCondition::kSymmetry || b.shape.type == ShapeType::kBox) continue;
    double side = 0;
    for (int d = 0; d < s.dimension - 1; ++d) side += (position[d] - b.shape.point[d]) * b.shape.normal[d];
    if (side >= 1.5 * s.solver.dx) continue;
    image = position;
    for (int d = 0; d < s.dimension - 1; ++d) image[d] -= 2 * side * b.shape.normal[d];
    return true;
  }
  return false;
}

// The share of a gauge's horizontal B-spline footprint (1.5 cells each way) that water can occupy: 1 in open
// water, about 1/2 for a gauge on a wall (a symmetry plane is not a wall: the gauge counts the image beyond it). The gauge divides the water volume it counts by it, so a gauge next to
// a wall reads the depth, not a part of it. The share is summed over the points where the particles of water at
// rest sit, the seeding lattice (ppc^(1/D) per cell and axis, at (k + 1/2) spacings from the frame's origin, as
// for water boxes that start on a multiple of the spacing, as the basin's do), just above the ground: the gauge
// sums point weights of particles, and the continuous integral of the truncated B-spline differs from that sum
// (a gauge half a cell from a wall read 1.2 % of the depth too high with it: +2.7 mm at t = 0). Over the whole lattice the weights add up to exactly ppc^((D-1)/D) per
// cell area whatever the gauge's position, so in open water the share is 1 to round-off.
inline double gauge_open_fraction(const Scene& s, const Vec3d& position, double ground) {
  const int up = s.dimension - 1;
  const double dx = s.solver.dx;
  const double spacing = particle_spacing(s);
  // Lattice points within the footprint on each horizontal axis.
  std::vector<double> pts[2];
  for (int d = 0; d < up; ++d) {
    const long k0 = static_cast<long>(std::floor((position[d] - 1.5 * dx) / spacing - 0.5)) - 1;
    const long k1 = static_cast<long>(std::ceil((position[d] + 1.5 * dx) / spacing - 0.5)) + 1;
    for (long k = k0; k <= k1; ++k) pts[d].push_back((k + 0.5) * spacing);
  }
  if (up == 1) pts[1] = {0.0};
  double all = 0, open = 0;
  for (const double pa : pts[0])
    for (const double pb : pts[1]) {
      const double w = bspline_weight((pa - position[0]) / dx) * (up == 2 ? bspline_weight((pb - position[1]) / dx) : 1.0);
      if (w <= 0) continue;
      Vec3d p = position;
      p[0] = pa;
      if (up == 2) p[1] = pb;
      p[up] = ground + 0.5 * dx;
      all += w;
      if (!inside_solid(s, p, false)) open += w;
    }
  return all > 0 ? open / all : 0.0;
}

template <class Solver>
class InstrumentSet {
 public:
  explicit InstrumentSet(const Scene& scene) : scene_(scene), pressures_(scene) {
    const int D = scene.dimension;
    for (const auto& g : scene.instruments.gauges) {
      record_.gauges[g.name].components = 1;
      gauges_.push_back({g.name, 1.0 / g.rate_hz, 0.0});
      ground_.push_back(ground_level(scene, g.position));
      open_.push_back(gauge_open_fraction(scene, g.position, ground_.back()));
      Vec3d image{};
      has_image_.push_back(gauge_image(scene, g.position, image));
      image_.push_back(image);
    }
    for (const auto& p : scene.instruments.probes) {
      record_.probes[p.name].components = D;
      probes_.push_back({p.name, 1.0 / p.rate_hz, 0.0});
    }
    for (const auto& l : scene.instruments.loads) {
      record_.loads[l.name].components = D;
      loads_.push_back({l.name, 1.0 / l.rate_hz, 0.0});
      for (size_t w = 0; w < scene.boundaries.size(); ++w)
        if (scene.boundaries[w].name == l.boundary) load_wall_.push_back(w);
      load_impulse_.push_back(std::vector<double>(D, 0.0));
      load_since_.push_back(0.0);
    }
    for (const auto& c : scene.instruments.sections) {
      SectionSeries& r = record_.sections[c.name];
      r.x_m = c.x_m;
      Vec3d at{};
      at[0] = c.x_m;
      r.floor_m = ground_level(scene, at);
      if (D == 3) {  // bins of width dx across the domain, edges on the grid lines
        r.bin_width_m = scene.solver.dx;
        const long nb = std::max(1L, std::lround((scene.domain_hi[1] - scene.domain_lo[1]) / scene.solver.dx));
        for (long j = 0; j < nb; ++j) r.y.push_back(scene.domain_lo[1] + (j + 0.5) * scene.solver.dx);
      }
      const long nz = std::max(1L, std::lround(std::ceil((scene.domain_hi[D - 1] - r.floor_m) / scene.solver.dx)));
      for (long j = 0; j < nz; ++j) r.z.push_back(r.floor_m + (j + 0.5) * scene.solver.dx);
      sections_.push_back({c.name, 1.0 / c.rate_hz, 0.0});
    }
    diag_period_ = 1.0 / scene.instruments.diagnostics_rate_hz;
    for (const char* k : {"time", "mass", "kinetic", "potential", "elastic", "total", "dt", "max_speed", "step"})
      record_.diagnostics[k];
  }

  const Record& record() const { return record_; }

  // The record so far and when each instrument samples next (solver/checkpoint.h).
  void checkpoint(StateArchive& ar) {
    ar.section("instruments");
    ar(record_);
    for (auto* clocks : {&gauges_, &probes_, &loads_, &sections_}) {
      ar.expect("instruments", clocks->size());
      for (Clock& c : *clocks) ar(c.next);
    }
    ar.expect("instruments.loads", load_impulse_.size());
    for (auto& li : load_impulse_) ar(li);
    ar(load_since_);
    pressures_.checkpoint(ar);
    ar(next_diag_);
  }

  // Accumulates the impulse the water gave each load-cell boundary over the last step.
  void add_impulses(const std::vector<double>& impulse_per_wall, double /*dt*/) {
    const int D = scene_.dimension;
    for (size_t k = 0; k < loads_.size(); ++k)
      for (int d = 0; d < D; ++d) load_impulse_[k][d] += impulse_per_wall[load_wall_[k] * D + d];
  }

  // Samples every instrument whose next sample time has come (all of them when `force`).
  void sample(const Solver& s, double t, double dt, bool force) {
    const int D = scene_.dimension;
    for (size_t k = 0; k < gauges_.size(); ++k)
      if (due(gauges_[k], t, force)) {
        auto& ts = record_.gauges[gauges_[k].name];
        ts.time.push_back(t);
        const Gauge& g = scene_.instruments.gauges[k];
        const double z = g.reading == GaugeReading::kConnected ? connected_elevation(s, scene_, g, ground_[k], heights_)
                                                                : gauge_elevation(s, g);
        ts.values.push_back(z - g.datum);
      }
    for (size_t k = 0; k < probes_.size(); ++k)
      if (due(probes_[k], t, force)) {
        auto& ts = record_.probes[probes_[k].name];
        ts.time.push_back(t);
        double v[3] = {0, 0, 0};  // probe_velocity fills the first D
        probe_velocity(s, scene_.instruments.probes[k].position, v);
        for (int d = 0; d < D; ++d) ts.values.push_back(v[d]);
      }
    for (size_t k = 0; k < loads_.size(); ++k)
      if (due(loads_[k], t, force)) {
        auto& ts = record_.loads[loads_[k].name];
        const double span = t - load_since_[k];
        ts.time.push_back(t);
        // The mean force over the sampling interval (impulse / time), so no impact between samples is lost.
        for (int d = 0; d < D; ++d) ts.values.push_back(span > 0 ? load_impulse_[k][d] / span : 0.0);
        std::fill(load_impulse_[k].begin(), load_impulse_[k].end(), 0.0);
        load_since_[k] = t;
      }
    pressures_.step(s, t, dt, force, record_);  // every step: a probe reports its interval's mean
    for (size_t k = 0; k < sections_.size(); ++k)
      if (due(sections_[k], t, force)) section_sample(s, t, record_.sections[sections_[k].name]);
    Clock diag{"", diag_period_, next_diag_};
    if (due(diag, t, force)) {
      next_diag_ = diag.next;
      auto e = t == 0 ? s.energy() : s.last_energy();
      auto& r = record_.diagnostics;
      r["time"].push_back(t);
      r["mass"].push_back(s.total_mass());
      r["kinetic"].push_back(e.kinetic);
      r["potential"].push_back(e.potential);
      r["elastic"].push_back(e.elastic);
      r["total"].push_back(e.total());
      r["dt"].push_back(dt);
      r["max_speed"].push_back(s.max_speed());
      r["step"].push_back(static_cast<double>(s.steps()));
    }
  }

 private:
  struct Clock {
    std::string name;
    double period;
    double next;
  };
  static bool due(Clock& c, double t, bool force) {
    if (!force && t + 1e-12 < c.next) return false;
    while (c.next <= t + 1e-12) c.next += c.period;
    return true;
  }

  // Free-surface elevation: the ground under the gauge plus the depth of water above it, the water's volume
  // per unit area there. Each particle's volume counts with the quadratic B-spline weight of its horizontal
  // distance from the gauge (in cells), as a grid node would weigh it: over a regular lattice of spacing dx/k
  // these weights add up to exactly k per cell of height, so water at rest reads its depth whatever the
  // particles' offset from the gauge, and a moving free surface reads smoothly, not in one-particle steps (on a
  // lattice stretched to fit a box, dx/k not whole, to within the weights' aliasing: 2.4e-6 of the depth for
  // the Waseda basin's 196 columns in 3.91 m at dx = 0.04 m). Volumes are the particles' reference volumes
  // (mass / rho), which leaves out the compression rho g h / 2K (6e-4 of the depth at h = 0.23 m, K = 2e6 Pa).
  // Spray above the surface counts as the water it is; an air pocket under it does not.
  // (The gauge this replaces took the top of the particle column within dx/2 of the gauge, rising from the
  // ground without a gap: inside a broken bore a gap of one cell near the floor made single samples read the
  // bare floor, 0.2 m spikes in WG1 that a calibration's RMS misfit could not see past.)
  double gauge_elevation(const Solver& s, const Gauge& g) {
    const int D = s.dim();
    const int up = D - 1;
    const double dx = scene_.solver.dx, inv_dx = 1.0 / dx;
    const size_t k = static_cast<size_t>(&g - scene_.instruments.gauges.data());
    GaugeTerm term{up, {g.position[0], up == 2 ? g.position[1] : 0.0}, 0, inv_dx};
    term.lowest = ground_[k] - 0.25 * dx;  // water below the ground here is beside the gauge, not under it
    double weight;
    sum_particles(s, term, &weight);
    if (has_image_[k]) {  // the water's mirror image across the symmetry plane
      GaugeTerm mirrored = term;
      for (int d = 0; d < up; ++d) mirrored.g[d] = image_[k][d];
      double w;
      sum_particles(s, mirrored, &w);
      weight += w;
    }
    const double area = up == 2 ? dx * dx : dx;
    const double depth = open_[k] > 0 ? weight / (area * open_[k]) : 0.0;
    return ground_[k] + depth;
  }

  // Velocity at a point: particles within the quadratic B-spline support (1.5 dx), weighted by it. NaN when
  // no water is there (a dry probe has no velocity).
  void probe_velocity(const Solver& s, const Vec3d& p, double* v) const {
    const int D = s.dim();
    double sum[ProbeTerm::kValues];  // the weight, then the weighted velocity
    sum_particles(s, ProbeTerm{D, {p[0], p[1], p[2]}, 1.0 / scene_.solver.dx}, sum);
    for (int d = 0; d < D; ++d) v[d] = sum[0] > 0 ? sum[1 + d] / sum[0] : std::numeric_limits<double>::quiet_NaN();
  }

  // Depth and depth-averaged streamwise velocity across a section. Each particle counts with the quadratic
  // B-spline weight of its distance from the plane (in cells), as a grid node at x_m would weigh it: summed over
  // a regular lattice of any spacing dx/k these weights add up to exactly k, so water at rest reads its depth
  // without the one-particle jumps of a +-dx/2 window (gauge_elevation weighs the same way). Across y a
  // particle falls in one bin (bins partition the width, so the flux summed over bins is the total). Depth is
  // the water's volume per unit area at the reference density, mass / rho (the particles' reference volumes,
  // which weigh the velocity too: the section's mass flux over its mass); the compression it leaves out is
  // rho g h / 2K (6e-4 at h = 0.23 m and K = 2e6 Pa). The velocity is also kept per layer dx thick: 0.1 m before
  // the quay wall the flow is sheared (measured at dx = 0.04 m: 0.11 m/s at the floor, 0.74 m/s at the top),
  // and a replay with the depth-averaged velocity alone carries too little momentum over the quay.
  void section_sample(const Solver& s, double t, SectionSeries& r) {
    const int D = s.dim();
    const double dx = scene_.solver.dx, inv_dx = 1.0 / dx;
    const size_t nb = r.bins(), nz = r.z.size();
    acc_m_.assign(nb, 0.0);
    acc_u_.assign(nb, 0.0);
    acc_zm_.assign(nb * nz, 0.0);
    acc_zu_.assign(nb * nz, 0.0);
    for (size_t i = 0; i < s.n(); ++i) {
      const double q = std::fabs(double(s.x(0, i)) - r.x_m) * inv_dx;
      if (q >= 1.5) continue;
      const double w = (q < 0.5 ? 0.75 - q * q : 0.5 * (1.5 - q) * (1.5 - q)) * double(s.volume(i));
      size_t j = 0;
      if (D == 3) {
        const double b = std::floor((double(s.x(1, i)) - scene_.domain_lo[1]) * inv_dx);
        j = static_cast<size_t>(std::clamp(b, 0.0, double(nb - 1)));
      }
      acc_m_[j] += w;
      acc_u_[j] += w * double(s.v(0, i));
      const double layer = std::floor((double(s.x(D - 1, i)) - r.floor_m) * inv_dx);
      const size_t l = j * nz + static_cast<size_t>(std::clamp(layer, 0.0, double(nz - 1)));
      acc_zm_[l] += w;
      acc_zu_[l] += w * double(s.v(0, i));
    }
    const double area = dx * (D == 3 ? r.bin_width_m : 1.0);
    r.time.push_back(t);
    for (size_t j = 0; j < nb; ++j) {
      r.depth.push_back(acc_m_[j] / area);
      r.velocity.push_back(acc_m_[j] > 0 ? acc_u_[j] / acc_m_[j] : 0.0);
      for (size_t l = j * nz; l < (j + 1) * nz; ++l)
        r.profile.push_back(acc_zm_[l] > 0 ? acc_zu_[l] / acc_zm_[l] : r.velocity.back());
    }
  }

  const Scene& scene_;
  Record record_;
  std::vector<Clock> gauges_, probes_, loads_, sections_;
  std::vector<double> acc_m_, acc_u_, acc_zm_, acc_zu_;
  std::vector<double> ground_, open_;  // per gauge: ground level, open share of its footprint
  std::vector<char> has_image_;        // per gauge: whether its footprint reaches a symmetry plane,
  std::vector<Vec3d> image_;           // and its image across it
  std::vector<double> heights_;        // a connected gauge's column (solver/connected_depth.h)
  PressureProbeSet<Solver> pressures_;
  std::vector<size_t> load_wall_;
  std::vector<std::vector<double>> load_impulse_;
  std::vector<double> load_since_;
  double diag_period_ = 0.01, next_diag_ = 0;
};

}  // namespace flume
