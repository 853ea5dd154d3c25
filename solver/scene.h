// The scene: what a run simulates, parsed and validated once from JSON into plain structs.
// No JSON type travels past scene.cpp. Frame: the last axis is vertical (z up in 3D, (x, z) in 2D).
#pragma once
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "common/input/overrides.h"

namespace flume {

enum class Precision { kFloat, kDouble };
// paper eq. 2; kSymmetry: an axis-aligned half-space that is a mirror plane of the flow (mpm::SymmetryPlane)
enum class BoundaryCondition { kSticky, kSlip, kSeparate, kSymmetry };
enum class ShapeType { kBox, kHalfSpace };

using Vec3d = std::array<double, 3>;  // 2D scenes use the first two entries (x, z); the third is 0.

// An analytic solid. Box: the solid is [lo, hi]. Half-space: the solid is {x : (x - point) . normal < 0},
// so `normal` points out of the solid into the fluid.
struct Shape {
  ShapeType type = ShapeType::kBox;
  Vec3d lo{}, hi{};
  Vec3d point{}, normal{};
};

// Signed distance from x to a shape, negative inside the solid (a 2D scene passes dim = 2).
double shape_distance(const Shape& s, const Vec3d& x, int dim);

struct Boundary {
  std::string name;
  Shape shape;
  BoundaryCondition condition = BoundaryCondition::kSeparate;
  double friction = 0.0;  // Coulomb coefficient for `separate`
  double roughness = 0.0;  // m, equivalent sand roughness k_s of a bed stress by the wall law (0: none)
  Vec3d velocity{};       // boundary velocity v_b of eq. 2
  unsigned subcell_axes = 0;  // a box: the axes across which its faces act below a cell (mpm::subcell_cover)
};

// Water initially at rest, filling a box. With `hydrostatic`, it starts with the pressure rho g (surface - z)
// (zero above `surface`), `surface` defaulting to the box's top.
struct WaterRegion {
  Vec3d lo{}, hi{};
  bool hydrostatic = true;
  double surface = 0.0;
};

// The solver: MLS-MPM (the default) or weakly compressible SPH (solver/sph/, docs/sph.md).
enum class SolverMethod { kMpm, kSph };

struct SolverSettings {
  SolverMethod method = SolverMethod::kMpm;
  double dx = 0.01;
  int ppc = 4;  // particles per cell per axis is ppc^(1/D) rounded: ppc must be a perfect power (2D: 1,4,9; 3D: 1,8,27)
  int max_particles = 100000000;  // bound on the particles the water boxes seed, checked before allocating
  double cfl = 0.4;
  double flip = 0.0;  // MPM's G2P: share of the particle's own velocity kept (FLIP) against APIC's
  Precision precision = Precision::kDouble;
  double end_time = 1.0;
  double max_dt = 1e-3;  // s, an upper bound on the adaptive step
  Vec3d gravity{};       // default: -9.80665 on the vertical axis
};

struct FluidSettings {
  double density = 1000.0;       // kg/m^3
  double bulk_modulus = 2.0e7;   // Pa
  double gamma = 7.0;            // Tait/Murnaghan exponent
  double viscosity = 1.0e-3;     // Pa s
  double jbar_psi = 0.0;         // paper eqs. 3-4: 0 = plain MLS-MPM, 1 = fully grid-averaged J
};

// SPH's own settings (the `sph` section; read whatever the method, used when solver.method is sph). Particles
// sit on the same lattice as MPM's (dx / ppc^(1/D) apart), so gauges and masses are the same.
enum class SphViscosity { kLaminarSps, kArtificial };
enum class SphShifting { kNone, kLind };
enum class SphBoundary { kMdbc, kDbc };
enum class SphSlip { kWall, kNoSlip, kFreeSlip };
struct SphSettings {
  double coefh = 1.0;  // smoothing length h = coefh sqrt(D) spacing (DualSPHysics; the study: h = sqrt(3) spacing)
  double cfl = 0.2;    // dt = cfl min(sqrt(h / |a|max), h / (c0 + h max visc)) (DualSPHysics' step condition)
  double density_diffusion = 0.1;  // delta of the Fourtakas et al. (2020) term; 0: none
  SphViscosity viscosity = SphViscosity::kLaminarSps;
  double artificial_alpha = 0.01;  // Monaghan's alpha, with viscosity "artificial"
  SphShifting shifting = SphShifting::kLind;  // particle shifting (Lind et al. 2012), as the study runs it
  double shifting_coef = 2.0;                 // A of dr = -A h |u| dt grad C (the study: 2)
  double shifting_threshold = 1.5;            // free surface below this div r (DualSPHysics: 1.5 2D, 2.75 3D)
  // Walls and debris: modified dynamic boundary conditions (English et al. 2022), or DBC (Crespo et al.
  // 2007).
  SphBoundary boundary = SphBoundary::kMdbc;
  // With mDBC, the velocity walls show the water: their own (DualSPHysics' "DBC vel=0"), or from the water's
  // at their ghost nodes, no slip or free slip (DualSPHysics' SlipMode 2 and 3).
  SphSlip slip = SphSlip::kWall;
};

// What a gauge reads (solver/connected_depth.h): the water's volume per unit area over the ground (the
// default), or, as a wire or resistance gauge, the top of the water connected to the ground.
enum class GaugeReading { kVolume, kConnected };
struct Gauge {
  std::string name;
  Vec3d position{};      // horizontal position; the vertical entry is ignored
  double rate_hz = 100;
  double datum = 0.0;    // elevation is reported relative to this level (m)
  GaugeReading reading = GaugeReading::kVolume;
};
struct Probe {
  std::string name;
  Vec3d position{};
  double rate_hz = 100;
};
// A vertical cross-section x = x_m (issue 3): at its rate, the water depth and the depth-averaged streamwise
// velocity across it (one value in 2D; bins of width dx across y in 3D), the record an `inflow` replays.
struct Section {
  std::string name;
  double x_m = 0;
  double rate_hz = 200;
};
// A pressure probe (issue 30): the water's pressure on a solid face at a point, as a flush-mounted pressure
// sensor reads it (solver/pressure_probes.h).
struct PressureProbe {
  std::string name;
  Vec3d position{};  // a point on the face
  Vec3d normal{};    // the face's outward normal (out of the solid, into the water), unit length
  double rate_hz = 1000;
};
struct LoadCell {
  std::string name;
  std::string boundary;  // name of the boundary whose grid-node reaction is summed
  double rate_hz = 1000;
};

struct Instruments {
  std::vector<Gauge> gauges;
  std::vector<Probe> probes;
  std::vector<LoadCell> loads;
  std::vector<PressureProbe> pressure_probes;
  std::vector<Section> sections;
  double diagnostics_rate_hz = 100;
  double snapshot_rate_hz = 0;  // 0: no particle snapshots
};

// The vacuum hold of a tsunami basin's reservoir (issue 3): the fraction f(t) of the weight of the water
// above still-water level that the vacuum carries. f = 1 holds it, f = 0 releases it.
enum class ForcingModel { kNone, kExponential, kTable };
struct ReservoirForcing {
  ForcingModel model = ForcingModel::kNone;
  double t99_s = 1.0;                               // exponential: f = exp(-t ln(100) / t99)
  std::vector<std::array<double, 2>> table;         // table: control points (t s, f), piecewise linear
  double hold(double t) const;                      // f(t) in [0, 1]
};

// A tsunami wave basin generated from a few parameters (the `basin`, `reservoir` and `obstacles` sections
// of a scene; see scenes/waseda/README.md). Kept on the scene for the forcing, the metrics and the reports.
struct Basin {
  bool present = false;
  std::string span = "full";       // full | half | slice (2D)
  std::string region = "basin";    // basin | apron (x >= inflow.x_m only, driven by the inflow)
  double length_m = 9.0, width_m = 4.0, still_water_m = 0.23, quay_x_m = 4.45, apron_height_m = 0.255;
  double slice_y_m = 2.0;          // the slice's position across (2D)
  double reservoir_length_m = 0.50, gate_thickness_m = 0.04, gate_height_m = 0.10, fill_level_m = 0.90;
  ReservoirForcing forcing;
  std::string obstacles_layout = "0x0";
  std::vector<std::string> obstacle_names;  // boundaries that are obstacles (columns)
  std::vector<std::array<Vec3d, 2>> obstacle_boxes;  // their solid boxes (lo, hi), 3D frame
};

// Rigid debris (issue 4): boxes with 6-DOF dynamics, contact with the flume and each other (Bullet), coupled
// both ways with the water through the grid (solver/debris_coupling.h). 3D scenes only.
struct DebrisBody {
  std::string name;                        // D1, D2, ... (HDF5 /debris/<name>, metrics <name>.*)
  Vec3d size{};                            // full edge lengths along the body axes, m
  Vec3d position{};                        // centre of mass, m
  std::array<double, 4> orientation{1, 0, 0, 0};  // body -> world quaternion (w, x, y, z)
  double mass = 0.0;                       // kg (from `mass`, or `density` x volume)
};
struct DebrisSettings {
  bool present = false;
  // Coulomb friction and restitution; the paper's Table 2 ranges (friction 0.15-0.80 flume, 0.05-0.80 debris;
  // restitution 0.30-0.60 flume, 0.40-0.70 debris). Defaults: the SPH team's Chrono values (section 4.2).
  double friction_flume = 0.425, friction_debris = 0.2;
  double restitution_flume = 0.55, restitution_debris = 0.6;
  double density = 418.5;  // kg/m^3: the Waseda container, 0.226 kg in 0.15 x 0.06 x 0.06 m
  // How the layout was generated in a basin scene (for reports): count, layers, placement, first row's x.
  int count = 0, layers = 0;
  std::string placement;
  double row_x_m = 0.0;
  double resample_hz = 30.0;      // the experiment's accelerometer rate
  double record_rate_hz = 1000.0; // solver-rate trajectory samples kept per second (0: every step)
  // At rest at the end of a run: slower than rest_speed_m_s over the run's last rest_hold_s (metrics
  // <k>.at_rest, <k>.moving_until_s, debris.at_rest_count). 1 cm/s at 1:40 is 6 cm/s full scale.
  double rest_speed_m_s = 0.01;
  double rest_hold_s = 1.0;
  std::vector<DebrisBody> bodies;
};

// Water entering through the vertical plane x = x_m (issue 3, `waseda_apron`): it replays the depth and
// depth-averaged velocity that a section instrument of another run recorded there (solver/inflow.h). The
// record is read and checked with the scene.
struct InflowSettings {
  bool present = false;
  std::string record;          // a result.h5 holding /sections/<section>
  std::string section;
  double x_m = 4.35;
  double buffer_cells = 3;     // the kinematic buffer upstream of the plane, in cells (the stencil's reach)
  double y_lo = 0, y_hi = 0;   // 3D: the lateral extent of the water at the plane
  // The record: time (nt), bin centres y (nb, 3D records; empty for 2D ones), depth and velocity (nt x nb).
  int record_dimension = 2;
  double record_bin_width_m = 0, record_floor_m = 0;
  std::vector<double> time, y, depth, velocity;
  std::vector<double> z, profile;  // velocity per layer (nt x nb x nz); empty: the depth average drives every row
  size_t bins() const { return y.empty() ? 1 : y.size(); }
};

struct Scene {
  std::string file;  // where it was read from, for messages
  // The scene as read, with the --set overrides applied (before a basin's expansion): written to run.json and
  // result.h5, so that a run's outputs say what it ran.
  std::string source_json;
  std::string name;
  int dimension = 3;
  Vec3d domain_lo{}, domain_hi{};
  BoundaryCondition domain_walls = BoundaryCondition::kSeparate;
  double domain_wall_friction = 0.0;
  SolverSettings solver;
  FluidSettings fluid;
  SphSettings sph;
  std::vector<WaterRegion> water;
  std::vector<Boundary> boundaries;
  Instruments instruments;
  Basin basin;
  DebrisSettings debris;
  InflowSettings inflow;
};

// Particles per cell along one axis, ppc^(1/D) (load_scene requires a whole number), and the spacing of the
// lattice they are seeded on, dx / ppc^(1/D): SPH's particle size, and the scale the instruments read water
// at.
inline int particles_per_axis(int ppc, int dim) {
  const long n = std::lround(std::pow(double(ppc), 1.0 / dim));
  return n < 1 ? 1 : static_cast<int>(n);
}
inline double particle_spacing(const Scene& s) {
  return s.solver.dx / particles_per_axis(s.solver.ppc, s.dimension);
}

// Reads, overrides and validates a scene. Throws flume::InputError naming the file, the field path and
// what is allowed. Unknown fields are errors (a typo in a campaign's parameter path must not pass silently).
Scene load_scene(const std::string& file, const std::vector<Override>& overrides = {});
Scene parse_scene_text(const std::string& json_text, const std::string& file_label,
                       const std::vector<Override>& overrides = {});

// The scene file's text, bounded (common/input/json_input.h) before it is read: campaigns and calibrations
// read it once and parse it per design point.
std::string read_scene_file(const std::string& file);

const char* to_string(BoundaryCondition c);
const char* to_string(Precision p);
const char* to_string(SolverMethod m);
const char* to_string(ForcingModel m);

}  // namespace flume
