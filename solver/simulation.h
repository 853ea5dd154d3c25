// A running simulation of a scene, independent of dimension, precision and backend.
#pragma once
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "solver/scene.h"

namespace flume {

class DebrisCoupling;
class StateArchive;

enum class Backend { kCpu, kCuda };

struct SimulationOptions {
  Backend backend = Backend::kCpu;
  int threads = 0;  // 0: OpenMP's default
};

// A sampled time series with `components` values per sample (1 for a gauge, D for a probe or load).
struct TimeSeries {
  int components = 1;
  std::vector<double> time;
  std::vector<double> values;  // row-major, time.size() x components
  size_t size() const { return time.size(); }
  double at(size_t i, int c = 0) const { return values[i * components + c]; }
};

// A section's record: per sample, per bin across y (one bin in 2D), the depth (water volume per unit area,
// mass / density, m) and the mass-weighted mean streamwise velocity (m/s; 0 where dry).
struct SectionSeries {
  double x_m = 0, floor_m = 0, bin_width_m = 0;  // bin_width_m = 0 in 2D (per unit width)
  std::vector<double> y;                          // bin centres (3D)
  std::vector<double> time, depth, velocity;      // depth, velocity: time.size() x bins, row-major
  // The vertical profile of the streamwise velocity: layers dx thick from the floor (centres z), per sample and
  // bin (time.size() x bins x z.size()); a layer without water holds its bin's depth-averaged velocity.
  std::vector<double> z, profile;
  size_t bins() const { return y.empty() ? 1 : y.size(); }
};

// Everything the instruments recorded. Names are the instruments' names from the scene.
struct Record {
  std::map<std::string, TimeSeries> gauges;  // water elevation above the gauge's datum (m)
  std::map<std::string, TimeSeries> probes;  // velocity (m/s), D components
  std::map<std::string, TimeSeries> loads;   // force of the water on a boundary (N; N/m in 2D), D components
  std::map<std::string, TimeSeries> pressures;  // pressure probes: the water's pressure on a face (Pa)
  std::map<std::string, SectionSeries> sections;
  std::map<std::string, std::vector<double>> diagnostics;  // time, mass, kinetic, potential, elastic, total, dt, max_speed, step
};

// kKilled: stopped by SIGTERM or SIGINT before the end time (solver/run.h); the solvers never return it.
enum class RunStatus { kRunning, kOk, kUnstable, kKilled };

// Cost counters, as `flume run` reports them.
struct Cost {
  double wall_s = 0;
  long steps = 0;
  size_t particles = 0;
  double particle_steps_per_s = 0;
  double peak_rss_mb = 0;
};

class Simulation {
 public:
  virtual ~Simulation() = default;
  // Advances one adaptive step. Returns kUnstable (and sets message()) when the step produced NaN/Inf,
  // a particle left the domain or the energy grew beyond what gravity and forcing can supply.
  virtual RunStatus step() = 0;
  virtual double time() const = 0;
  virtual double last_dt() const = 0;
  virtual long steps() const = 0;
  virtual size_t particle_count() const = 0;
  virtual double total_mass() const = 0;
  virtual const Record& record() const = 0;
  virtual const std::string& message() const = 0;
  // Particle positions (n x 3, the unused axis 0 in 2D) and velocities, for snapshots and tests.
  virtual void particle_positions(std::vector<double>& xyz) const = 0;
  virtual void particle_velocities(std::vector<double>& vel) const = 0;
  virtual void particle_pressures(std::vector<double>& p) const = 0;
  // Grid memory actually allocated (bytes) and blocks active now: what the sparse grid saves.
  virtual size_t grid_bytes() const = 0;
  virtual size_t active_blocks() const = 0;
  virtual size_t particle_bytes() const = 0;
  // Wall seconds spent in each stage of the steps so far, in step order (empty where a backend does not
  // time them), and the memory traffic of one step as the backend counts it (bytes; 0: not counted).
  virtual std::vector<std::pair<std::string, double>> stage_seconds() const { return {}; }
  virtual double bytes_per_step() const { return 0; }
  // Particle pairs within the kernel's support summed over every force evaluation so far (SPH; 0 for MPM).
  virtual long neighbour_interactions() const { return 0; }
  // Linear and angular momentum (about the origin), for conservation checks: 3 components each.
  virtual void momentum(double linear[3], double angular[3]) const = 0;
  // Sets particle velocities to v(x) = v0 + omega x (x - centre) (3D; in 2D omega is about the out-of-plane
  // axis and only omega[2] is used). For tests and initial conditions.
  virtual void set_rigid_velocity(const double v0[3], const double omega[3], const double centre[3]) = 0;
  // The debris and their recorded trajectories; null when the scene has none.
  virtual const DebrisCoupling* debris() const { return nullptr; }
  virtual DebrisCoupling* debris() { return nullptr; }
  // Writes the whole state into `ar`, or reads it back (ar.loading()), into a simulation built from the same
  // scene (solver/checkpoint.h). A backend that cannot throws InputError.
  virtual void checkpoint(StateArchive& ar);
};

// The records' state for a checkpoint.
void checkpoint_state(StateArchive& ar, TimeSeries& s);
void checkpoint_state(StateArchive& ar, SectionSeries& s);
void checkpoint_state(StateArchive& ar, Record& r);

// Builds the solver for the scene's dimension and precision. Throws InputError for an unavailable backend.
std::unique_ptr<Simulation> make_simulation(const Scene& scene, const SimulationOptions& options);

bool cuda_available();  // built with CUDA and a device present

}  // namespace flume
