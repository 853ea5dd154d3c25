// Scene JSON -> plain structs, with every value checked once here.
#include "solver/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "common/errors.h"
#include "common/input/field_reader.h"
#include "common/input/json_input.h"
#include "solver/inflow.h"
#include "solver/scene_fields.h"

namespace flume {
namespace {

using json = nlohmann::json;

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

using input::type_name;

using Reader = input::FieldReader;
using input::Bounds;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxSceneJsonBytes = 60000;

// What the solver allocates from a scene, bounded before it is (docs/reliability.md, "Input limits"): the
// particles its water boxes seed and the cells across its domain.
// solver.max_particles: default 1e8 (~25 GB in double precision in 3D: a large GPU node), at most this, within the
// int the field is read into (scene_fields.cpp).
constexpr int kHardMaxParticles = 2000000000;
constexpr double kMaxCellsPerAxis = 4.0e6;         // block keys pack 21 bits per axis (2^21 blocks of 4 cells)

// Particles seeded per box (seed_water in solver/seeding.h: at most ceil(L / spacing) per axis, at least 1),
// in double so that a dx of 1e-9 m cannot overflow the count.
void check_allocation_bounds(const Scene& sc, Reader& root, int dim) {
  const auto& s = sc.solver;
  const double per_axis = particles_per_axis(s.ppc, dim);
  const double spacing = s.dx / per_axis;
  for (int d = 0; d < dim; ++d) {
    const double cells = (sc.domain_hi[d] - sc.domain_lo[d]) / s.dx;
    if (cells > kMaxCellsPerAxis)
      root.fail("solver.dx", "gives " + fmt(cells) + " cells across the domain on axis " + std::to_string(d) +
                                 " (allowed: at most " + fmt(kMaxCellsPerAxis) + ", i.e. dx >= " +
                                 fmt((sc.domain_hi[d] - sc.domain_lo[d]) / kMaxCellsPerAxis) + " m)");
  }
  double total = 0;
  for (std::size_t w = 0; w < sc.water.size(); ++w) {
    double n = 1;
    for (int d = 0; d < dim; ++d) {
      const double along = (sc.water[w].hi[d] - sc.water[w].lo[d]) / spacing;
      // Thinner than half a particle spacing, the box has no lattice row of its own: one particle a spacing
      // wide would carry it (dx 1e9 m on the Waseda basin left 3 particles).
      if (along < 0.5)
        root.fail("solver.dx", "does not resolve water." + std::to_string(w) + ": it is " +
                                   fmt(sc.water[w].hi[d] - sc.water[w].lo[d]) + " m on axis " + std::to_string(d) +
                                   ", under half a particle spacing (0.5 dx / ppc^(1/D) = " + fmt(0.5 * spacing) +
                                   " m); allowed: dx <= " +
                                   fmt(2 * per_axis * (sc.water[w].hi[d] - sc.water[w].lo[d])) + " m");
      n *= std::max(1.0, std::ceil(along));
    }
    total += n;
  }
  if (total > s.max_particles)
    root.fail("solver.dx", "seeds about " + fmt(total) + " particles at dx " + fmt(s.dx) + " m and ppc " +
                               std::to_string(s.ppc) + " (allowed: at most solver.max_particles = " +
                               std::to_string(s.max_particles) + ", which may be raised to " +
                               std::to_string(kHardMaxParticles) + " where the memory allows)");
}

Shape read_shape(Reader& r, int dim) {
  Shape s;
  s.type = r.choice<ShapeType>("type", {{"box", ShapeType::kBox}, {"half_space", ShapeType::kHalfSpace}});
  if (s.type == ShapeType::kBox) {
    s.lo = r.vec("lo", dim);
    s.hi = r.vec("hi", dim);
    for (int d = 0; d < dim; ++d)
      if (!(s.hi[d] > s.lo[d])) r.fail("hi", "must exceed lo on every axis (axis " + std::to_string(d) + ")");
  } else {
    s.point = r.vec("point", dim);
    s.normal = r.vec("normal", dim);
    double n2 = 0;
    for (int d = 0; d < dim; ++d) n2 += s.normal[d] * s.normal[d];
    if (n2 < 1e-24) r.fail("normal", "must be a non-zero vector");
    for (int d = 0; d < dim; ++d) s.normal[d] /= std::sqrt(n2);
  }
  return s;
}

}  // namespace

double shape_distance(const Shape& s, const Vec3d& x, int dim) {
  if (s.type == ShapeType::kHalfSpace) {
    double d = 0;
    for (int i = 0; i < dim; ++i) d += (x[i] - s.point[i]) * s.normal[i];
    return d;
  }
  double outside2 = 0, inside = -kInf;
  for (int i = 0; i < dim; ++i) {
    const double q = std::max(s.lo[i] - x[i], x[i] - s.hi[i]);
    if (q > 0) outside2 += q * q;
    inside = std::max(inside, q);
  }
  return outside2 > 0 ? std::sqrt(outside2) : inside;
}

namespace {

// Is the solid overlapping the open box (lo, hi) by more than tol? Tested on a lattice of the box's points,
// which is exact for half-spaces (corners) and for boxes (the lattice includes the overlap's corners).
bool solid_overlaps_box(const Shape& s, const Vec3d& lo, const Vec3d& hi, int dim, double tol) {
  if (s.type == ShapeType::kBox) {
    for (int d = 0; d < dim; ++d)
      if (std::min(hi[d], s.hi[d]) - std::max(lo[d], s.lo[d]) <= tol) return false;
    return true;
  }
  // Half-space: the minimum of (x - p).n over the box is at a corner.
  double m = 0;
  for (int d = 0; d < dim; ++d) m += (s.normal[d] > 0 ? lo[d] : hi[d]) * s.normal[d] - s.point[d] * s.normal[d];
  return m < -tol;
}

// ---- tsunami basin -----------------------------------------------------------------------------------------
// A `basin` section generates the domain, walls, gate, quay, obstacles, water and the standard instruments
// of a reservoir-driven tsunami basin (defaults: the Waseda basin of Goseberg et al. 2016b as the study's
// Tables 1-2 give it). Geometry is defined once in the 3D frame (x downstream from the reservoir's back wall,
// y across, z up) and mapped to the scene's frame: a 2D scene is the x-z slice at basin.slice_y_m, a `half`
// span keeps y <= width/2 with a symmetry (slip) plane on the centreline.

Basin read_basin(const json& root, const std::string& file, int dim) {
  static const json empty = json::object();
  Basin B;
  B.present = true;
  Reader b(root.at("basin"), basin_doc(), "basin", file);
  B.span = b.choice_or("span", dim == 2 ? "slice" : "full");
  if ((B.span == "slice") != (dim == 2))
    b.fail("span", dim == 2 ? "must be slice in a 2D scene" : "must be full or half in a 3D scene (slice is 2D)");
  B.still_water_m = b.number("still_water_m");
  B.quay_x_m = b.number("quay_x_m");
  B.apron_height_m = b.number("apron_height_m");
  B.length_m = b.number("length_m", Bounds{B.quay_x_m, 1000.0, true, false});
  B.width_m = b.number("width_m");
  B.slice_y_m = b.number_or("slice_y_m", B.width_m / 2, Bounds{0.0, B.width_m});
  const std::string walls = b.choice("walls");
  b.number("wall_friction");
  if (b.number("bed_roughness_m") > 0 && walls == "sticky")
    b.fail("bed_roughness_m", "sticky walls already hold the water (must be 0 with walls: sticky)");
  b.choice("instruments");
  B.region = b.choice("region");
  b.finish();
  if (B.region == "apron") {
    // The apron alone (issue 3): the basin downstream of inflow.x_m, driven by the inflow's replay of a section
    // record. Nothing upstream is modelled, so a reservoir has no meaning here.
    if (!root.contains("inflow"))
      b.fail("region", "apron needs an inflow section {\"record\": \"RUN/result.h5\", \"section\": \"apron_inflow\", "
                       "\"x_m\": 4.35} to drive it");
    if (root.contains("reservoir"))
      throw InputError(file, "reservoir", "the apron region has no reservoir (the inflow drives it): remove this section");
  }

  Reader r(root.contains("reservoir") ? root.at("reservoir") : empty, reservoir_doc(), "reservoir", file);
  B.reservoir_length_m = r.number("length_m", Bounds{0.0, B.quay_x_m, true, true});
  B.gate_thickness_m = r.number("gate_thickness_m");
  B.fill_level_m = r.number("fill_level_m", Bounds{B.still_water_m, 100.0});
  B.gate_height_m = r.number("gate_height_m", Bounds{0.0, B.fill_level_m, true, false});
  if (B.reservoir_length_m + B.gate_thickness_m >= B.quay_x_m)
    r.fail("length_m", "the reservoir and gate must end before the quay at x = " + fmt(B.quay_x_m));
  {
    Reader f = r.object("forcing");
    auto& F = B.forcing;
    F.model = f.choice<ForcingModel>("model",
                                     {{"none", ForcingModel::kNone},
                                      {"exponential", ForcingModel::kExponential},
                                      {"table", ForcingModel::kTable}});
    F.t99_s = f.number("t99_s");
    if (f.has("table")) {
      const json& t = f.raw("table");
      auto bad = [&](const std::string& at, const std::string& what) { f.fail("table" + at, what); };
      if (!t.is_array() || t.size() < 2) bad("", "must be an array of at least 2 points [t_s, f]");
      for (size_t i = 0; i < t.size(); ++i) {
        const json& pt = t[i];
        const std::string at = "." + std::to_string(i);
        if (!pt.is_array() || pt.size() != 2 || !pt[0].is_number() || !pt[1].is_number())
          bad(at, "must be a point [t_s, f] of two numbers");
        const double ti = pt[0].get<double>(), fi = pt[1].get<double>();
        if (!(ti >= 0) || !std::isfinite(ti)) bad(at + ".0", "time must be a finite number >= 0 (got " + fmt(ti) + ")");
        if (!(fi >= 0 && fi <= 1)) bad(at + ".1", "hold fraction must be in [0, 1] (got " + fmt(fi) + ")");
        if (i > 0 && !(ti > F.table.back()[0]))
          bad(at + ".0", "times must increase (got " + fmt(ti) + " after " + fmt(F.table.back()[0]) + ")");
        F.table.push_back({ti, fi});
      }
    } else if (F.model == ForcingModel::kTable) {
      f.fail("table", "is required by model table (an array of points [t_s, f])");
    }
    f.finish();
  }
  r.finish();

  Reader o(root.contains("obstacles") ? root.at("obstacles") : empty, obstacles_doc(), "obstacles", file);
  B.obstacles_layout = o.choice("layout");
  o.number("size_m");
  o.number("spacing_m");
  o.number("row_spacing_m");
  o.number("first_row_x_m", Bounds{B.quay_x_m, B.length_m});
  o.finish();
  return B;
}

// Writes the basin's domain, boundaries, water and instruments into the scene's JSON (which must not set
// them itself), so that the strict parse below validates them like any hand-written scene.
void expand_basin(json& root, Basin& B, const std::string& file, int dim) {
  for (const char* k : {"domain", "water"})
    if (root.contains(k))
      throw InputError(file, k, "is generated by the basin section: remove it, or remove `basin` and describe the scene by hand");
  const json& bs = root.at("basin");
  const json& os = root.contains("obstacles") ? root.at("obstacles") : json::object();
  double dx = 0.02;
  if (root.contains("solver") && root["solver"].is_object() && root["solver"].contains("dx") && root["solver"]["dx"].is_number())
    dx = root["solver"]["dx"].get<double>();
  const std::string walls = bs.value("walls", std::string("slip"));
  const double wall_friction = bs.value("wall_friction", 0.0);
  const double bed_roughness = bs.value("bed_roughness_m", 0.0);
  const bool half = B.span == "half";
  const double W = half ? B.width_m / 2 : B.width_m;  // modelled width
  const double pad = 3 * dx;
  const double top = std::max(B.fill_level_m, B.apron_height_m + 0.3) + 0.1;
  const double L = B.length_m, Lr = B.reservoir_length_m, Lg = Lr + B.gate_thickness_m;
  // The apron region starts at the inflow plane, with room upstream of it for the inflow's buffer.
  const bool apron = B.region == "apron";
  double x_in = 0, x_lo = -pad;
  if (apron) {
    json& in = root["inflow"];
    if (!in.is_object()) throw InputError(file, "inflow", std::string("must be an object, got ") + type_name(in));
    if (in.contains("x_m") && !in["x_m"].is_number()) throw InputError(file, "inflow.x_m", "must be a number");
    if (in.contains("buffer_cells") && !in["buffer_cells"].is_number())
      throw InputError(file, "inflow.buffer_cells", "must be a number");
    x_in = in.value("x_m", 4.35);
    if (!(x_in > 0 && x_in < B.quay_x_m))
      throw InputError(file, "inflow.x_m", "must lie in (0, " + fmt(B.quay_x_m) + "), upstream of the quay, in an apron "
                                           "region (got " + fmt(x_in) + ")");
    x_lo = x_in - (in.value("buffer_cells", 3.0) + 3) * dx;
    if (dim == 3 && !in.contains("y_m")) in["y_m"] = json::array({0.0, W});
  }

  auto at = [&](double x, double y, double z) {
    return dim == 2 ? json::array({x, z}) : json::array({x, y, z});
  };
  auto box = [&](const std::string& name, double x0, double x1, double y0, double y1, double z0, double z1) {
    return json{{"name", name}, {"type", "box"}, {"lo", at(x0, y0, z0)}, {"hi", at(x1, y1, z1)},
                {"condition", walls}, {"friction", wall_friction}};
  };
  auto plane = [&](const std::string& name, json point, json normal) {
    return json{{"name", name}, {"type", "half_space"}, {"point", point}, {"normal", normal},
                {"condition", walls}, {"friction", wall_friction}};
  };
  // The grid is symmetric about the centreline: the domain starts a whole number of half cells below it. A half
  // span's symmetry plane must lie on a grid line or midway (mpm::SymmetryPlane), and the full basin then has the
  // same grid on that side, so that the two compare node for node (-pad itself wherever dx divides the half width).
  const double centre = 0.5 * B.width_m;
  const double y_lo = centre - 0.5 * dx * std::ceil(2 * (centre + pad) / dx - 1e-9);
  root["domain"] = {{"lo", at(x_lo, y_lo, -pad)}, {"hi", at(L + pad, W + pad, top + pad)}, {"walls", "slip"}};
  json bnd = json::array();
  if (!apron) bnd.push_back(plane("back_wall", at(0, 0, 0), at(1, 0, 0)));
  json floor = plane("floor", at(0, 0, 0), at(0, 0, 1));
  floor["roughness_m"] = bed_roughness;
  bnd.push_back(floor);
  bnd.push_back(plane("end_wall", at(L, 0, 0), at(-1, 0, 0)));
  if (dim == 3) {
    bnd.push_back(plane("side_wall", at(0, 0, 0), at(0, 1, 0)));
    if (half) {
      json sym = plane("symmetry", at(0, W, 0), at(0, -1, 0));
      sym["condition"] = "symmetry";  // a mirror plane of the flow: exact, not a wall (mpm::SymmetryPlane)
      sym["friction"] = 0.0;
      bnd.push_back(sym);
    } else {
      bnd.push_back(plane("far_side_wall", at(0, W, 0), at(0, -1, 0)));
    }
  }
  if (!apron) {
    // The gate's lower edge, whose height campaigns and calibrations vary, acts below a cell (mpm::subcell_cover).
    json gate = box("gate", Lr, Lg, -pad, W + pad, B.gate_height_m, top + 2 * pad);
    gate["subcell_axes"] = json::array({dim - 1});
    bnd.push_back(gate);
  }
  json quay = box("quay", B.quay_x_m, L + 2 * pad, -pad, W + pad, -2 * pad, B.apron_height_m);
  quay["roughness_m"] = bed_roughness;
  bnd.push_back(quay);
  // Obstacles: 0.10 m square columns, 5 across centred on the basin, rows 0.45 m apart.
  const int rows = B.obstacles_layout == "5x2" ? 2 : B.obstacles_layout == "5x1" ? 1 : 0;
  const double size = os.value("size_m", 0.10), spacing = os.value("spacing_m", 0.325);
  const double row_spacing = os.value("row_spacing_m", 0.45), x0 = os.value("first_row_x_m", 5.11);
  json loads = json::array();
  for (int rr = 0; rr < rows; ++rr)
    for (int c = 0; c < 5; ++c) {
      const double xl = x0 + rr * row_spacing;
      const double yl = B.width_m / 2 - size / 2 + (c - 2) * spacing;
      double yh = yl + size;
      if (dim == 2 && !(yl <= B.slice_y_m && B.slice_y_m <= yh)) continue;  // not cut by the slice
      if (half && yl >= W) continue;                                       // in the mirrored half
      // A column the symmetry plane cuts stays whole: the grid beyond the plane is the mirror of the modelled side
      // (mpm::SymmetryPlane), and a node inside it must be held as in the full basin.
      const std::string name = "column_r" + std::to_string(rr + 1) + "c" + std::to_string(c + 1);
      bnd.push_back(box(name, xl, xl + size, yl, yh, B.apron_height_m - 2 * pad, top + 2 * pad));
      B.obstacle_names.push_back(name);
      B.obstacle_boxes.push_back({Vec3d{xl, yl, B.apron_height_m - 2 * pad}, Vec3d{xl + size, yh, top + 2 * pad}});
      loads.push_back({{"name", "LC_r" + std::to_string(rr + 1) + "c" + std::to_string(c + 1)},
                       {"boundary", name}, {"rate_hz", 1200}});
    }
  if (!root.contains("boundaries")) root["boundaries"] = json::array();
  for (auto& b : bnd) root["boundaries"].push_back(b);

  // Water: the reservoir (its part above still water is what the vacuum holds), the gap under the gate, the
  // basin up to the quay. Released (`none`), the reservoir starts hydrostatic to its own surface; held, to
  // still-water level, the held layer above weighing nothing.
  const double still = B.still_water_m;
  const double res_surface = B.forcing.model == ForcingModel::kNone ? B.fill_level_m : still;
  root["water"] = json::array();
  if (apron) {  // still water from the inflow plane to the quay; the inflow brings the rest
    root["water"].push_back({{"lo", at(x_in, 0, 0)}, {"hi", at(B.quay_x_m, W, still)}, {"surface", still}});
  } else {
    root["water"].push_back({{"lo", at(0, 0, 0)}, {"hi", at(Lr, W, B.fill_level_m)}, {"surface", res_surface}});
    root["water"].push_back({{"lo", at(Lr, 0, 0)}, {"hi", at(Lg, W, std::min(B.gate_height_m, still))}, {"surface", still}});
    root["water"].push_back({{"lo", at(Lg, 0, 0)}, {"hi", at(B.quay_x_m, W, still)}, {"surface", still}});
  }

  // Instruments of the study's Table 1 in this frame: gauges report eta above still water.
  if (bs.value("instruments", std::string("waseda")) == "waseda") {
    json& inst = root["instruments"];
    if (inst.is_null()) inst = json::object();
    // Half a cell off a wall; on a symmetry plane a gauge counts the water's image (solver/instruments.h), so
    // the half basin's WG1 stands on the centreline as the full basin's does.
    auto across = [&](double y) { return std::clamp(y, 0.5 * dx, half ? W : W - 0.5 * dx); };
    auto horizontal = [&](double x, double y) { return dim == 2 ? json::array({x}) : json::array({x, across(y)}); };
    json gauges = json::array();
    const double wall_offset = 0.25;
    const std::array<std::pair<const char*, std::array<double, 2>>, 4> wg = {{{"WG1", {1.85, B.width_m / 2}},
                                                                                {"WG2", {3.64, wall_offset}},
                                                                                {"WG3", {4.69, wall_offset}},
                                                                                {"WG4", {6.15, wall_offset}}}};
    for (const auto& [name, p] : wg)
      if (p[0] > x_in)  // the apron region keeps the instruments downstream of its inflow plane
        gauges.push_back({{"name", name}, {"position", horizontal(p[0], p[1])}, {"rate_hz", 100}, {"datum_m", still}});
    json probes = json::array();
    if (!apron) probes.push_back({{"name", "ADV"}, {"position", at(3.64, across(0.35), still - 0.10)}, {"rate_hz", 100}});
    // The section an apron run replays (issue 3): depth and velocity at x = 4.35 m, 0.10 m before the quay.
    json sections = json::array();
    if (!apron) sections.push_back({{"name", "apron_inflow"}, {"x_m", 4.35}, {"rate_hz", 200}});
    for (const char* k : {"gauges", "probes", "loads", "sections"})
      if (!inst.contains(k)) inst[k] = json::array();
    for (auto& g : gauges) inst["gauges"].push_back(g);
    for (auto& p : probes) inst["probes"].push_back(p);
    for (auto& l : loads) inst["loads"].push_back(l);
    for (auto& c : sections) inst["sections"].push_back(c);
  }
  root.erase("basin");
  root.erase("reservoir");
  root.erase("obstacles");
}


// A basin scene's `debris` section may describe the Waseda layout instead of listing bodies: `count` (3|6)
// containers in `layers` (1|2), `placement` upstream|downstream of the obstacles, the first row's upstream face
// at `row_x_m`. This writes the bodies it means into debris.bodies (boxes sized `size_m` along x, y, z, 3 side
// by side `gap_m` apart, centred across the basin, resting on the apron with a 0.5 mm gap as the STAR-CCM+ team
// placed theirs, section 4.3) and returns the layout for the reports. D1-D3 are the bottom layer (or first row)
// from low to high y, D4-D6 the top layer (or second row).
void expand_debris_layout(json& root, Basin& B, DebrisSettings& layout, const std::string& file, int dim) {
  if (!root.contains("debris")) return;
  json& d = root["debris"];
  if (!d.is_object()) throw InputError(file, "debris", std::string("must be an object, got ") + type_name(d));
  if (d.contains("bodies")) return;  // listed by hand
  Reader r(d, debris_doc(), "debris", file);
  if (dim != 3) r.fail("", "debris need a 3D scene (the rigid bodies are 3D): use waseda_3d or remove `debris`");
  if (B.span == "half")
    r.fail("", "the debris layout is not mirror-symmetric about the centreline: use basin.span = full");
  layout.count = static_cast<int>(r.integer("count"));
  if (layout.count != 3 && layout.count != 6) r.fail("count", "must be 3 or 6 (got " + std::to_string(layout.count) + ")");
  layout.layers = static_cast<int>(r.integer_or("layers", layout.count == 6 ? 2 : 1));
  if (layout.count == 3 && layout.layers != 1) r.fail("layers", "must be 1 when count is 3 (three containers make one layer)");
  layout.placement = r.choice("placement");
  // Downstream: 0.30 m past the last obstacle row's downstream face (the study gives no position; an
  // assumption, stated in docs/debris.md).
  const json& os = root.contains("obstacles") ? root.at("obstacles") : json::object();
  const int rows = B.obstacles_layout == "5x2" ? 2 : B.obstacles_layout == "5x1" ? 1 : 0;
  const double obstacle_end = os.value("first_row_x_m", 5.11) +
                              (rows > 0 ? (rows - 1) * os.value("row_spacing_m", 0.45) + os.value("size_m", 0.10) : 0.0);
  const double default_x = layout.placement == "upstream" ? 4.65 : obstacle_end + 0.30;
  layout.row_x_m = r.number_or("row_x_m", default_x, Bounds{B.quay_x_m, B.length_m});
  const Vec3d size = r.vec("size_m", 3, Vec3d{0.06, 0.15, 0.06});
  for (int a = 0; a < 3; ++a)
    if (!(size[a] > 0)) r.fail("size_m", "edge lengths must be > 0");
  const double gap = r.number("gap_m");
  for (const char* k : {"friction", "restitution", "density", "resample_hz", "record_rate_hz", "rest_speed_m_s",
                        "rest_hold_s"})
    if (r.has(k)) r.accept(k);
  r.finish();
  const int per_layer = 3;
  const int stacks = layout.count / per_layer / layout.layers;  // rows one behind the other (6 in 1 layer: 2)
  json bodies = json::array();
  int k = 0;
  for (int layer = 0; layer < layout.layers; ++layer)
    for (int row = 0; row < stacks; ++row)
      for (int c = 0; c < per_layer; ++c) {
        const double x = layout.row_x_m + row * 2 * size[0] + 0.5 * size[0];
        const double y = B.width_m / 2 + (c - 1) * (size[1] + gap);
        const double z = B.apron_height_m + 0.0005 + layer * (size[2] + 0.0005) + 0.5 * size[2];
        bodies.push_back({{"name", "D" + std::to_string(++k)}, {"size", {size[0], size[1], size[2]}},
                          {"position", {x, y, z}}});
      }
  for (const char* key : {"count", "layers", "placement", "row_x_m", "size_m", "gap_m"}) d.erase(key);
  d["bodies"] = bodies;
}

double ReservoirForcing_hold(const ReservoirForcing& F, double t) {
  switch (F.model) {
    case ForcingModel::kNone: return 0.0;
    case ForcingModel::kExponential: return F.t99_s > 0 ? std::exp(-t * std::log(100.0) / F.t99_s) : 0.0;
    case ForcingModel::kTable: {
      const auto& T = F.table;
      if (t <= T.front()[0]) return T.front()[1];
      for (size_t i = 1; i < T.size(); ++i)
        if (t <= T[i][0]) return T[i - 1][1] + (T[i][1] - T[i - 1][1]) * (t - T[i - 1][0]) / (T[i][0] - T[i - 1][0]);
      return T.back()[1];
    }
  }
  return 0.0;
}

Scene parse(const json& root_json, const std::string& file) {
  Scene sc;
  sc.file = file;
  Reader root(root_json, scene_doc(), "", file);
  sc.name = root.string("name");
  sc.dimension = static_cast<int>(root.integer("dimension"));
  const int dim = sc.dimension;
  const int up = dim - 1;

  {
    Reader r = root.object("domain");
    if (!root.has("domain")) root.fail("domain", "is required (an object with lo and hi)");
    sc.domain_lo = r.vec("lo", dim);
    sc.domain_hi = r.vec("hi", dim);
    for (int d = 0; d < dim; ++d)
      if (!(sc.domain_hi[d] > sc.domain_lo[d])) r.fail("hi", "must exceed domain.lo on every axis");
    sc.domain_walls = r.choice<BoundaryCondition>("walls",
                                                  {{"sticky", BoundaryCondition::kSticky},
                                                   {"slip", BoundaryCondition::kSlip},
                                                   {"separate", BoundaryCondition::kSeparate}});
    sc.domain_wall_friction = r.number("friction");
    r.finish();
  }

  {
    Reader r = root.object("solver");
    auto& s = sc.solver;
    s.method = r.choice<SolverMethod>("method", {{"mpm", SolverMethod::kMpm}, {"sph", SolverMethod::kSph}});
    double min_extent = kInf;
    for (int d = 0; d < dim; ++d) min_extent = std::min(min_extent, sc.domain_hi[d] - sc.domain_lo[d]);
    s.dx = r.number("dx", Bounds{0.0, min_extent / 4, true, false});
    s.ppc = static_cast<int>(r.integer_or("ppc", dim == 2 ? 4 : 8));
    s.max_particles = static_cast<int>(r.integer("max_particles"));
    const int per_axis = particles_per_axis(s.ppc, dim);
    int p = 1;
    for (int d = 0; d < dim; ++d) p *= per_axis;
    if (p != s.ppc)
      r.fail("ppc", std::string("must be a perfect ") + (dim == 2 ? "square (1, 4, 9, 16, ...)" : "cube (1, 8, 27, 64)") +
                        " so particles sit on a regular lattice (got " + std::to_string(s.ppc) + ")");
    s.cfl = r.number("cfl");
    s.flip = r.number("flip");
    if (s.flip > 0 && s.method == SolverMethod::kSph)
      r.fail("flip", "is MPM's transfer; SPH has none (must be 0 with solver.method sph)");
    s.precision = r.choice<Precision>("precision",
                                      {{"float", Precision::kFloat}, {"double", Precision::kDouble}});
    s.end_time = r.number("end_time");
    s.max_dt = r.number("max_dt");
    Vec3d g{};
    g[up] = -9.80665;
    s.gravity = r.vec("gravity", dim, g);
    r.finish();
  }

  {
    Reader r = root.object("sph");
    auto& p = sc.sph;
    p.coefh = r.number("coefh");
    p.cfl = r.number("cfl");
    p.density_diffusion = r.number("density_diffusion");
    p.viscosity = r.choice<SphViscosity>("viscosity",
                                         {{"laminar_sps", SphViscosity::kLaminarSps}, {"artificial", SphViscosity::kArtificial}});
    p.artificial_alpha = r.number("artificial_alpha");
    p.shifting = r.choice<SphShifting>("shifting", {{"none", SphShifting::kNone}, {"lind", SphShifting::kLind}});
    p.shifting_coef = r.number("shifting_coef");
    p.boundary =
        r.choice<SphBoundary>("boundary", {{"mdbc", SphBoundary::kMdbc}, {"dbc", SphBoundary::kDbc}});
    p.slip = r.choice<SphSlip>(
        "slip", {{"wall", SphSlip::kWall}, {"no_slip", SphSlip::kNoSlip}, {"free_slip", SphSlip::kFreeSlip}});
    if (p.slip != SphSlip::kWall && p.boundary != SphBoundary::kMdbc)
      r.fail("slip",
             "no_slip and free_slip set the walls' velocity from their ghost nodes: they need boundary mdbc");
    // div r is D inside the water: the threshold must lie below it.
    p.shifting_threshold =
        r.number_or("shifting_threshold", dim == 2 ? 1.5 : 2.75, Bounds{0.0, double(dim), true, true});
    r.finish();
  }

  {
    Reader r = root.object("fluid");
    auto& f = sc.fluid;
    f.density = r.number("density");
    f.bulk_modulus = r.number("bulk_modulus");
    f.gamma = r.number("gamma");
    f.viscosity = r.number("viscosity");
    f.jbar_psi = r.number("jbar_psi");
    r.finish();
  }

  {
    auto walls = root.objects("boundaries");
    std::set<std::string> names;
    for (auto& r : walls) {
      Boundary b;
      b.name = r.string_or("name", "boundary" + std::to_string(sc.boundaries.size()));
      if (!names.insert(b.name).second) r.fail("name", "duplicate boundary name '" + b.name + "'");
      b.shape = read_shape(r, dim);
      b.condition = r.choice<BoundaryCondition>("condition",
                                                {{"sticky", BoundaryCondition::kSticky},
                                                 {"slip", BoundaryCondition::kSlip},
                                                 {"separate", BoundaryCondition::kSeparate},
                                                 {"symmetry", BoundaryCondition::kSymmetry}});
      b.friction = r.number("friction");
      b.roughness = r.number("roughness_m");
      if (b.roughness > 0 && b.condition == BoundaryCondition::kSymmetry)
        r.fail("roughness_m", "a symmetry plane has no roughness (must be 0)");
      if (b.roughness > 0 && b.condition == BoundaryCondition::kSticky)
        r.fail("roughness_m", "a sticky wall already holds the water (must be 0)");
      b.velocity = r.vec("velocity", dim, Vec3d{});
      // Axes across which a box's faces act below a cell (mpm::subcell_cover), e.g. the gate's opening: [0..dim).
      if (r.has("subcell_axes")) {
        const json& axes = r.raw("subcell_axes");
        const std::string allowed = "an array of axis indices in [0, " + std::to_string(dim - 1) + "]";
        if (!axes.is_array()) r.fail("subcell_axes", "must be " + allowed);
        for (const auto& a : axes) {
          if (!a.is_number_integer() || a.get<int>() < 0 || a.get<int>() >= dim)
            r.fail("subcell_axes", "must be " + allowed + " (got " + a.dump() + ")");
          b.subcell_axes |= 1u << a.get<int>();
        }
      }
      if (b.subcell_axes && b.shape.type != ShapeType::kBox) r.fail("subcell_axes", "applies to boxes only");
      if (b.subcell_axes && b.condition == BoundaryCondition::kSticky)
        r.fail("subcell_axes", "applies to slip and separate boundaries (sticky nodes have no partial rule)");
      if (b.condition == BoundaryCondition::kSymmetry) {
        // A mirror plane of the flow (mpm::SymmetryPlane): a fixed, frictionless, axis-aligned plane whose
        // reflection maps grid nodes onto grid nodes.
        if (b.shape.type != ShapeType::kHalfSpace) r.fail("condition", "symmetry needs type half_space (a plane)");
        int axis = -1;
        for (int d = 0; d < dim; ++d)
          if (std::fabs(std::fabs(b.shape.normal[d]) - 1.0) < 1e-12) axis = d;
        if (axis < 0) r.fail("normal", "a symmetry plane's normal must lie along a grid axis");
        for (int d = 0; d < dim; ++d)
          if (b.velocity[d] != 0.0) r.fail("velocity", "a symmetry plane does not move (must be 0)");
        if (b.friction != 0.0) r.fail("friction", "a symmetry plane has no friction (must be 0)");
        const double cells = 2 * (b.shape.point[axis] - sc.domain_lo[axis]) / sc.solver.dx;
        if (std::fabs(cells - std::round(cells)) > 1e-6)
          r.fail("point", "a symmetry plane must lie on a grid line or midway between two: axis " +
                              std::to_string(axis) + " at " + fmt(b.shape.point[axis]) + " m is " +
                              fmt(0.5 * cells) + " cells (dx " + fmt(sc.solver.dx) + ") from domain.lo " +
                              fmt(sc.domain_lo[axis]) + " m; allowed: a whole or half number of cells");
        for (const auto& o : sc.boundaries)
          if (o.condition == BoundaryCondition::kSymmetry)
            r.fail("condition", "one symmetry plane per scene (found '" + o.name + "' already)");
      }
      r.finish();
      sc.boundaries.push_back(b);
    }
  }

  {
    auto regions = root.objects("water");
    if (regions.empty()) root.fail("water", "is required: a non-empty array of boxes {lo, hi}");
    for (auto& r : regions) {
      WaterRegion w;
      r.choice("type");  // box, the only shape
      w.lo = r.vec("lo", dim);
      w.hi = r.vec("hi", dim);
      for (int d = 0; d < dim; ++d) {
        if (!(w.hi[d] > w.lo[d])) r.fail("hi", "must exceed lo on every axis (axis " + std::to_string(d) + ")");
        // The grid needs two cells of margin inside the domain for the quadratic stencil and the walls.
        const double lo_ok = sc.domain_lo[d] + 2 * sc.solver.dx, hi_ok = sc.domain_hi[d] - 2 * sc.solver.dx;
        if (w.lo[d] < lo_ok - 1e-12 || w.hi[d] > hi_ok + 1e-12)
          r.fail(w.lo[d] < lo_ok - 1e-12 ? "lo" : "hi",
                 "water must lie inside the domain at least 2 cells (2 dx) from its edge: axis " + std::to_string(d) +
                     " allows [" + fmt(lo_ok) + ", " + fmt(hi_ok) + "], got [" + fmt(w.lo[d]) + ", " + fmt(w.hi[d]) +
                     "]");
      }
      // Initial pressure: hydrostatic below a free surface (default: the region's top), so that water at rest
      // starts in equilibrium instead of falling onto its own compression and ringing acoustically.
      w.hydrostatic = r.boolean("hydrostatic");
      w.surface = r.number_or("surface", w.hi[dim - 1], Bounds{w.lo[dim - 1], 1e6});
      // Water placed inside a solid would be expelled violently at t = 0: forbidden.
      for (const auto& b : sc.boundaries)
        if (solid_overlaps_box(b.shape, w.lo, w.hi, dim, 0.25 * sc.solver.dx))
          r.fail("", "water region overlaps solid boundary '" + b.name + "'; water may only fill free space");
      r.finish();
      sc.water.push_back(w);
    }
    check_allocation_bounds(sc, root, dim);
  }

  {
    Reader inst = root.object("instruments");
    auto& I = sc.instruments;
    std::set<std::string> names;
    auto unique = [&](Reader& r, const std::string& n) {
      if (!names.insert(n).second) r.fail("name", "duplicate instrument name '" + n + "'");
    };
    auto inside = [&](Reader& r, const char* key, const Vec3d& p, int axes) {
      for (int d = 0; d < axes; ++d)
        if (p[d] < sc.domain_lo[d] || p[d] > sc.domain_hi[d])
          r.fail(key, "must lie inside the domain on axis " + std::to_string(d) + " ([" + fmt(sc.domain_lo[d]) +
                          ", " + fmt(sc.domain_hi[d]) + "], got " + fmt(p[d]) + ")");
    };
    for (auto& r : inst.objects("gauges")) {
      Gauge g;
      g.name = r.string("name");
      unique(r, g.name);
      g.position = r.vec("position", dim - 1);  // horizontal coordinates only
      inside(r, "position", g.position, dim - 1);
      g.rate_hz = r.number("rate_hz");
      g.datum = r.number("datum_m");
      g.reading = r.choice<GaugeReading>("reading",
                                         {{"volume", GaugeReading::kVolume}, {"connected", GaugeReading::kConnected}});
      r.finish();
      I.gauges.push_back(g);
    }
    for (auto& r : inst.objects("probes")) {
      Probe p;
      p.name = r.string("name");
      unique(r, p.name);
      p.position = r.vec("position", dim);
      inside(r, "position", p.position, dim);
      p.rate_hz = r.number("rate_hz");
      r.finish();
      I.probes.push_back(p);
    }
    for (auto& r : inst.objects("loads")) {
      LoadCell l;
      l.name = r.string("name");
      unique(r, l.name);
      l.boundary = r.string("boundary");
      bool found = false;
      for (const auto& b : sc.boundaries) found |= b.name == l.boundary;
      if (!found) r.fail("boundary", "names no boundary of this scene ('" + l.boundary + "')");
      l.rate_hz = r.number("rate_hz");
      r.finish();
      I.loads.push_back(l);
    }
    for (auto& r : inst.objects("pressure_probes")) {
      PressureProbe p;
      p.name = r.string("name");
      unique(r, p.name);
      p.position = r.vec("position", dim);
      inside(r, "position", p.position, dim);
      if (r.has("normal") == r.has("boundary"))
        r.fail(r.has("normal") ? "boundary" : "normal",
               "give the face's outward normal or the boundary the probe sits on, one of the two");
      if (r.has("normal")) {
        p.normal = r.vec("normal", dim);
        double n2 = 0;
        for (int d = 0; d < dim; ++d) n2 += p.normal[d] * p.normal[d];
        if (!(n2 > 1e-24)) r.fail("normal", "must be a non-zero vector (|normal| > 0), the face's outward normal");
        for (int d = 0; d < dim; ++d) p.normal[d] /= std::sqrt(n2);
      } else {
        // The face of a named boundary: a half-space's plane, or the box face nearest the point, which must lie
        // on it (within half a cell).
        const std::string name = r.string("boundary");
        const Boundary* b = nullptr;
        for (const auto& x : sc.boundaries)
          if (x.name == name) b = &x;
        if (!b) r.fail("boundary", "names no boundary of this scene ('" + name + "')");
        const double off = shape_distance(b->shape, p.position, dim);
        if (std::fabs(off) > 0.5 * sc.solver.dx)
          r.fail("position", "must lie on a face of boundary '" + name + "' (within dx/2 = " + fmt(0.5 * sc.solver.dx) +
                                 " m), is " + fmt(off) + " m from it");
        if (b->shape.type == ShapeType::kHalfSpace) {
          p.normal = b->shape.normal;
        } else {
          int axis = 0;
          double best = -kInf, sign = 1;
          for (int d = 0; d < dim; ++d)
            for (const double sg : {-1.0, 1.0}) {
              const double q = sg < 0 ? b->shape.lo[d] - p.position[d] : p.position[d] - b->shape.hi[d];
              if (q > best) best = q, axis = d, sign = sg;
            }
          p.normal = Vec3d{};
          p.normal[axis] = sign;
        }
      }
      p.rate_hz = r.number("rate_hz");
      r.finish();
      I.pressure_probes.push_back(p);
    }
    for (auto& r : inst.objects("sections")) {
      Section c;
      c.name = r.string("name");
      unique(r, c.name);
      c.x_m = r.number("x_m", Bounds{sc.domain_lo[0] + 2 * sc.solver.dx, sc.domain_hi[0] - 2 * sc.solver.dx});
      c.rate_hz = r.number("rate_hz");
      r.finish();
      I.sections.push_back(c);
    }
    I.diagnostics_rate_hz = inst.number("diagnostics_rate_hz");
    I.snapshot_rate_hz = inst.number("snapshot_rate_hz");
    inst.finish();
  }

  if (root.has("debris")) {
    Reader r = root.object("debris");
    auto& D = sc.debris;
    D.present = true;
    if (dim != 3) r.fail("", "debris need a 3D scene (the rigid bodies are 3D)");
    {
      Reader f = r.object("friction");
      D.friction_flume = f.number("flume");
      D.friction_debris = f.number("debris");
      f.finish();
      Reader e = r.object("restitution");
      D.restitution_flume = e.number("flume");
      D.restitution_debris = e.number("debris");
      e.finish();
    }
    D.density = r.number("density");
    D.resample_hz = r.number("resample_hz");
    D.record_rate_hz = r.number("record_rate_hz");
    D.rest_speed_m_s = r.number("rest_speed_m_s");
    D.rest_hold_s = r.number("rest_hold_s");
    auto list = r.objects("bodies");
    if (list.empty()) r.fail("bodies", "is required: a non-empty array of boxes {name, size, position}");
    std::set<std::string> names;
    for (auto& b : list) {
      DebrisBody body;
      body.name = b.string_or("name", "D" + std::to_string(D.bodies.size() + 1));
      if (!names.insert(body.name).second) b.fail("name", "duplicate debris name '" + body.name + "'");
      body.size = b.vec("size", 3);
      for (int a = 0; a < 3; ++a)
        if (!(body.size[a] > 0)) b.fail("size", "edge lengths must be > 0 (axis " + std::to_string(a) + ")");
      body.position = b.vec("position", 3);
      const double yaw = b.number("yaw_deg") * M_PI / 180.0;
      body.orientation = {std::cos(yaw / 2), 0.0, 0.0, std::sin(yaw / 2)};
      const double volume = body.size[0] * body.size[1] * body.size[2];
      body.mass = b.number_or("mass", D.density * volume);
      // Its bounding box must lie in the domain and clear every solid boundary (a box started inside a wall
      // would be thrown out of it).
      const double hx = 0.5 * std::hypot(body.size[0], body.size[1]) ;
      Vec3d lo{}, hi{};
      for (int a = 0; a < 3; ++a) {
        const double h = a < 2 && yaw != 0.0 ? hx : 0.5 * body.size[a];
        lo[a] = body.position[a] - h;
        hi[a] = body.position[a] + h;
        if (lo[a] < sc.domain_lo[a] + 2 * sc.solver.dx || hi[a] > sc.domain_hi[a] - 2 * sc.solver.dx)
          b.fail("position", "the body must lie inside the domain at least 2 cells from its edge (axis " +
                                 std::to_string(a) + ": [" + fmt(lo[a]) + ", " + fmt(hi[a]) + "] against [" +
                                 fmt(sc.domain_lo[a] + 2 * sc.solver.dx) + ", " + fmt(sc.domain_hi[a] - 2 * sc.solver.dx) + "])");
      }
      for (const auto& w : sc.boundaries)
        if (solid_overlaps_box(w.shape, lo, hi, 3, 1e-4))
          b.fail("position", "the body overlaps solid boundary '" + w.name + "'; place it in free space");
      b.finish();
      D.bodies.push_back(body);
    }
    r.finish();
  }
  if (root.has("inflow")) {
    Reader r = root.object("inflow");
    auto& F = sc.inflow;
    F.present = true;
    if (!r.has("record"))
      r.fail("record", "is required: the result.h5 of a run with a section instrument at this plane (e.g. "
                       "--set inflow.record=RUN/result.h5, a path relative to the working directory)");
    F.record = r.string("record");
    F.section = r.string("section");
    F.buffer_cells = r.number("buffer_cells");
    const double lo = sc.domain_lo[0] + (F.buffer_cells + 2) * sc.solver.dx;
    F.x_m = r.number("x_m", Bounds{lo, sc.domain_hi[0] - 2 * sc.solver.dx});
    if (dim == 3) {
      if (!r.has("y_m")) r.fail("y_m", "is required in 3D: [lo, hi], the lateral extent of the water at the plane");
      const Vec3d y = r.vec("y_m", 2);
      if (!(y[1] > y[0])) r.fail("y_m", "must be [lo, hi] with hi > lo");
      F.y_lo = y[0];
      F.y_hi = y[1];
    }
    r.finish();
  }
  root.finish();
  return sc;
}

}  // namespace

namespace {

// The scene's JSON with the overrides applied, not yet validated.
json parse_with_overrides(const std::string& json_text, const std::string& file_label,
                          const std::vector<Override>& overrides) {
  json root = input::parse_json_document(json_text, file_label);
  for (const auto& o : overrides) input::apply_override(root, o, file_label + " (--set " + o.path + ")");
  return root;
}

}  // namespace

std::string read_scene_file(const std::string& file) {
  return input::read_input_file(file, input::JsonLimits{}.max_bytes, "scene file");
}

Scene parse_scene_text(const std::string& json_text, const std::string& file_label,
                       const std::vector<Override>& overrides) {
  json root = parse_with_overrides(json_text, file_label, overrides);
  const std::string source = root.dump();
  // result.h5 keeps the scene whole as one attribute, and HDF5 caps an object's attributes at 64 KiB: a larger
  // scene (a 10 MB name, thousands of water boxes) ran to the end and then failed to write its result.
  if (source.size() > kMaxSceneJsonBytes)
    throw InputError(file_label, "",
                     "the scene with its overrides is " + std::to_string(source.size()) +
                         " bytes as compact JSON (allowed: at most " + std::to_string(kMaxSceneJsonBytes) +
                         ", stored whole in result.h5)");
  if (root.is_object() && root.contains("basin")) {
    if (!root.contains("dimension") || !root["dimension"].is_number_integer())
      throw InputError(file_label, "dimension", "is required (2 or 3)");
    const int dim = root["dimension"].get<int>();
    if (dim != 2 && dim != 3) throw InputError(file_label, "dimension", "must be 2 or 3");
    Basin basin = read_basin(root, file_label, dim);
    expand_basin(root, basin, file_label, dim);
    DebrisSettings layout;
    expand_debris_layout(root, basin, layout, file_label, dim);
    Scene sc = parse(root, file_label);
    if (sc.inflow.present) load_inflow_record(sc);
    sc.basin = basin;
    sc.debris.count = layout.count ? layout.count : static_cast<int>(sc.debris.bodies.size());
    sc.debris.layers = layout.layers;
    sc.debris.placement = layout.placement;
    sc.debris.row_x_m = layout.row_x_m;
    sc.source_json = source;
    return sc;
  }
  Scene sc = parse(root, file_label);
  if (sc.inflow.present) load_inflow_record(sc);
  sc.debris.count = static_cast<int>(sc.debris.bodies.size());
  sc.source_json = source;
  return sc;
}

Scene load_scene(const std::string& file, const std::vector<Override>& overrides) {
  return parse_scene_text(read_scene_file(file), file, overrides);
}

const char* to_string(BoundaryCondition c) {
  switch (c) {
    case BoundaryCondition::kSticky: return "sticky";
    case BoundaryCondition::kSlip: return "slip";
    case BoundaryCondition::kSymmetry: return "symmetry";
    default: return "separate";
  }
}
const char* to_string(Precision p) { return p == Precision::kFloat ? "float" : "double"; }
const char* to_string(SolverMethod m) { return m == SolverMethod::kSph ? "sph" : "mpm"; }
const char* to_string(ForcingModel m) {
  switch (m) {
    case ForcingModel::kExponential: return "exponential";
    case ForcingModel::kTable: return "table";
    default: return "none";
  }
}
double ReservoirForcing::hold(double t) const { return ReservoirForcing_hold(*this, t); }

}  // namespace flume
