// Weakly compressible SPH on the CPU (OpenMP), the second method beside MPM (docs/sph.md): DualSPHysics'
// formulation as the comparative study ran it (section 4.2). The physics is in sph_kernels.h; this file holds
// the particle arrays, the neighbour search (cell_list.h), the symplectic step and the plumbing to the
// instruments.
//
// Fluid particles are stored as structure-of-arrays and re-sorted by cell at the start of every step; the
// wall particles (fixed; their density from the water at their ghost nodes, mDBC, or evolved by continuity,
// DBC; floored at rho0) are sorted once. The fluid-fluid pairs are summed once for both particles, slabs of
// cells three apart at once (sph_launch.h), and so are the walls' pairs with the water; every other loop body
// writes only its own particle. Race-free without atomics, and the result does not depend on the number of
// threads.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

#include "common/errors.h"
#include "solver/checkpoint.h"
#include "solver/cpu_kernels.h"
#include "solver/debris_coupling.h"
#include "solver/inflow.h"
#include "solver/instruments.h"
#include "solver/interleave_axes.h"
#include "solver/mpm/boundaries.h"
#include "solver/seeding.h"
#include "solver/simulation.h"
#include "solver/sph/boundary_particles.h"
#include "solver/sph/cell_list.h"
#include "solver/sph/debris_particles.h"
#include "solver/sph/fluid_pair_lanes.h"
#include "solver/sph/gather_lanes.h"
#include "solver/sph/ghost_nodes.h"
#include "solver/sph/mirror.h"
#include "solver/sph/sph_debris.h"
#include "solver/sph/sph_kernels.h"
#include "solver/sph/sph_launch.h"

namespace flume {
namespace {

using sph::Accum;
using sph::Sym;

// Particles are sorted into cells at the start of a step and drift at most kDriftOverH h from there within it
// (the step is bounded so): the search reaches 2h plus that from a particle's present position to its
// neighbours' cells.
constexpr double kCellOverH = 1.0;
constexpr double kDriftOverH = 0.05;

template <int D, typename T>
class SphSolver final : public Simulation {
  static constexpr int kS = Sym<D>::kSize;

 public:
  SphSolver(const Scene& scene, const SimulationOptions& options) : scene_(scene), instruments_(scene_) {
    if (options.threads > 0) omp_set_num_threads(options.threads);
    spacing_ = particle_spacing(scene);
    setup_params();
    if (scene.debris.present) debris_ = std::make_unique<DebrisCoupling>(scene);
    seed_fluid();
    seed_walls();
    seed_debris();
    if (scene.inflow.present) {  // the buffer of the inflow boundary (solver/inflow.h), as MPM's
      inflow_ = std::make_unique<InflowBoundary<D, T>>(scene_, spacing_, particle_arrays());
      seed_inflow();
    }
    const Energy e = energy();
    energy0_ = e.total();
    // Slack of the energy audit, as MPM's: SPH with viscosity and density diffusion dissipates, so the total
    // may grow only by round-off and the settling of the walls; 1 % of the energy of lifting the water by its
    // own height bounds that, and a blow-up grows past it within a few steps.
    double zmin = 1e300, zmax = -1e300;
    for (const auto& w : scene.water) {
      zmin = std::min(zmin, w.lo[D - 1]);
      zmax = std::max(zmax, w.hi[D - 1]);
    }
    energy_slack_ = 0.01 * std::max({e.kinetic, mass_total_ * g_norm_ * (zmax - zmin), 1e-12});
    if (inflow_) energy_slack_ += inflow_->energy_scale();
    last_energy_ = e;
    instruments_.sample(*this, 0.0, 0.0, true);
  }

  RunStatus step() override {
    if (status_ != RunStatus::kRunning) return status_;
    if (!sort_fluid() || !sort_debris()) return status_;
    // The accelerations at t (the predictor's), then the step they allow.
    evaluate(x_, v_, rho_, rhow_, bodies_.x, bodies_.rho, time_, false);
    double dt = step_size();
    const double remaining = scene_.solver.end_time - time_;
    if (dt >= remaining) dt = remaining;
    if (!(dt > 0)) {
      status_ = RunStatus::kOk;
      return status_;
    }
    const T h = T(0.5 * dt);
    // Predictor to t + dt/2.
    sph::parallel_for(n_, [&](size_t i) {
      for (int d = 0; d < D; ++d) sph::predict(x_[d][i], v_[d][i], a_[d][i], T(dt), xh_[d][i], vh_[d][i]);
      rhoh_[i] = rho_[i] + h * drho_[i];
    });
    sph::parallel_for(nw_, [&](size_t k) { rhowh_[k] = std::max(T(P_.rho0), rhow_[k] + h * drhow_[k]); });
    bodies_.predict(T(dt), P_.rho0);
    // The mid-step evaluation also sums the shifting's concentration gradient, as DualSPHysics' corrector
    // interaction does.
    evaluate(xh_, vh_, rhoh_, rhowh_, bodies_.xh, bodies_.rhoh, time_ + 0.5 * dt, shifting_);
    // Corrector to t + dt with the mid-step rates; the hold's work on the water is energy supplied.
    const double lift = hold_lift(time_ + 0.5 * dt);
    double hold_work = 0;
    if (!held_.empty()) {
#pragma omp parallel for reduction(+ : hold_work) schedule(static)
      for (long i = 0; i < long(n_); ++i)
        hold_work += double(held_[i] * mass_[i]) * lift * double(vh_[D - 1][i]) * dt;
    }
    energy0_ += hold_work;
    sph::parallel_for(n_, [&](size_t i) {
      for (int d = 0; d < D; ++d) sph::correct(x_[d][i], v_[d][i], a_[d][i], T(dt));
      rho_[i] = sph::correct_density(rho_[i], rhoh_[i], drho_[i], T(dt));
    });
    if (shifting_) shift(T(dt));
    if (mirror_.active()) reflect_crossings();
    sph::parallel_for(nw_, [&](size_t k) {
      rhow_[k] = std::max(T(P_.rho0), sph::correct_density(rhow_[k], rhowh_[k], drhow_[k], T(dt)));
    });
    if (debris_) step_debris(dt);
    if (inflow_) apply_inflow(time_, time_ + dt);
    add_wall_impulses(dt);
    time_ += dt;
    dt_ = dt;
    ++steps_;
    audit(dt);
    if (status_ == RunStatus::kUnstable) {
      instruments_.sample(*this, time_, dt, true);
      return status_;
    }
    instruments_.add_impulses(load_impulse_, dt);
    std::fill(load_impulse_.begin(), load_impulse_.end(), 0.0);
    instruments_.sample(*this, time_, dt, false);
    if (time_ >= scene_.solver.end_time - 1e-12) status_ = RunStatus::kOk;
    return status_;
  }

  double time() const override { return time_; }
  double last_dt() const override { return dt_; }
  long steps() const override { return steps_; }
  size_t particle_count() const override { return n_; }
  double total_mass() const override { return mass_total_; }
  const Record& record() const override { return instruments_.record(); }
  const std::string& message() const override { return message_; }
  long neighbour_interactions() const override { return interactions_; }
  const DebrisCoupling* debris() const override { return debris_.get(); }
  DebrisCoupling* debris() override { return debris_.get(); }

  void particle_positions(std::vector<double>& xyz) const override {
    interleave_axes<D>(x_, n_, xyz);
  }
  void particle_velocities(std::vector<double>& vel) const override {
    interleave_axes<D>(v_, n_, vel);
  }
  void particle_pressures(std::vector<double>& p) const override {
    p.resize(n_);
    for (size_t i = 0; i < n_; ++i) p[i] = sph::tait_pressure(double(rho_[i]), Pd_);
  }
  size_t grid_bytes() const override {
    return (fluid_list_.start.capacity() + wall_list_.start.capacity()) * sizeof(uint32_t);
  }
  size_t active_blocks() const override { return grid_.count; }
  size_t particle_bytes() const override {
    return n_ * sizeof(T) * (5 * D + 5 + 2 * kS + (shifting_ ? D + 1 : 0)) + n_ * sizeof(Accum<D, T>) +
           nw_ * sizeof(T) * (2 * D + 6) +
           bodies_.n * (sizeof(T) * (4 * D + 7) + sizeof(int) + 3 * sizeof(double));
  }

  void momentum(double linear[3], double angular[3]) const override {
    double L[3] = {0, 0, 0}, A[3] = {0, 0, 0};
    for (size_t i = 0; i < n_; ++i) {
      double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
      for (int d = 0; d < D; ++d) {
        x[d] = x_[d][i];
        v[d] = v_[d][i];
      }
      const double m = mass_[i];
      for (int d = 0; d < 3; ++d) L[d] += m * v[d];
      if constexpr (D == 3) {
        A[0] += m * (x[1] * v[2] - x[2] * v[1]);
        A[1] += m * (x[2] * v[0] - x[0] * v[2]);
      }
      A[2] += m * (x[0] * v[1] - x[1] * v[0]);
    }
    for (int d = 0; d < 3; ++d) {
      linear[d] = L[d];
      angular[d] = A[d];
    }
  }

  void set_rigid_velocity(const double v0[3], const double omega[3], const double centre[3]) override {
    for (size_t i = 0; i < n_; ++i) {
      double r[3] = {0, 0, 0};
      for (int d = 0; d < D; ++d) r[d] = x_[d][i] - centre[d];
      if constexpr (D == 3) {
        v_[0][i] = T(v0[0] + omega[1] * r[2] - omega[2] * r[1]);
        v_[1][i] = T(v0[1] + omega[2] * r[0] - omega[0] * r[2]);
        v_[2][i] = T(v0[2] + omega[0] * r[1] - omega[1] * r[0]);
      } else {
        v_[0][i] = T(v0[0] - omega[2] * r[1]);
        v_[1][i] = T(v0[1] + omega[2] * r[0]);
      }
    }
    update_max_speed();
    const Energy e = energy();
    energy0_ = e.total();
    energy_slack_ = std::max(energy_slack_, 0.01 * e.kinetic);
  }

  // The fluid particles' state carried from step to step, in the checkpoint's order: what the checkpoint stores
  // and the block sort permutes. `optional`: empty unless the scene holds a reservoir.
  template <typename F>
  void for_each_particle_array(F&& f) {
    for (int d = 0; d < D; ++d) {
      f(x_[d], false);
      f(v_[d], false);
    }
    f(rho_, false);
    f(mass_, false);
    f(vol_, false);
    f(held_, true);
    f(tag_, true);
    for (auto& t : tau_) f(t, false);
  }

  // Everything a step reads that an earlier step wrote: the fluid particles in their last cell order (the
  // step's sort is stable, so the order it starts from decides the order it ends in, and with it every sum's),
  // their sub-particle stress, the walls' densities, the clock, the energy audit and the instruments. The cell
  // lists and the rates are rebuilt at the start of the next step, so a resumed run repeats the uninterrupted
  // one to the bit.
  void checkpoint(StateArchive& ar) override {
    ar.section(std::string("sph ") + std::to_string(D) + "D " + (sizeof(T) == 4 ? "float" : "double"));
    for_each_particle_array([&](std::vector<T>& a, bool) { ar(a); });
    ar.expect("wall particles", nw_);
    ar(rhow_);
    ar.expect("debris particles", bodies_.n);
    for (auto& o : bodies_.offset) ar(o);
    for (auto& o : bodies_.ghost) ar(o);
    ar(bodies_.body);
    ar(bodies_.mass);
    ar(bodies_.rho);
    if (debris_) debris_->checkpoint(ar);
    ar.expect("inflow", inflow_ ? 1 : 0);
    if (inflow_) inflow_->checkpoint(ar);
    ar.fields(time_, dt_, max_speed_, steps_, interactions_, energy0_, energy_slack_, last_energy_, mass_total_,
              status_, message_);
    instruments_.checkpoint(ar);
    if (!ar.loading()) return;
    const size_t n = x_[0].size();
    bool mismatch = rhow_.size() != nw_ || bodies_.body.size() != bodies_.n || bodies_.mass.size() != bodies_.n ||
                    bodies_.rho.size() != bodies_.n;
    for (const auto& o : bodies_.offset) mismatch = mismatch || o.size() != bodies_.n;
    for (const auto& o : bodies_.ghost) mismatch = mismatch || o.size() != bodies_.n;
    for_each_particle_array([&](std::vector<T>& a, bool optional) {
      mismatch = mismatch || ((!optional || !a.empty()) && a.size() != n);
    });
    // With an inflow the count is the checkpoint's (the boundary adds and removes particles).
    if (mismatch || (n != n_ && !inflow_))
      ar.fail("particles", "particle arrays of another length than the scene seeds");
    if (n != n_) resize_scratch(n);
    if (status_ == RunStatus::kUnstable) ar.fail("status", "the checkpointed run had gone unstable");
    if (debris_) bodies_.place(*debris_);
    // A finished run resumed to a later end time runs on.
    status_ = time_ < scene_.solver.end_time - 1e-12 ? RunStatus::kRunning : RunStatus::kOk;
  }

  // --- read access for the instruments ---
  int dim() const { return D; }
  size_t n() const { return n_; }
  T x(int d, size_t i) const { return x_[d][i]; }
  T v(int d, size_t i) const { return v_[d][i]; }
  T volume(size_t i) const { return vol_[i]; }  // reference volume: the particle's mass over rho0
  double max_speed() const { return max_speed_; }
  // The pressure probes read the walls' push through their particles (mpm::add_probe_push): per probe, the
  // last step's sum of weight times push along its normal (N s).
  static constexpr bool kProbesReadWallPush = true;
  const std::vector<double>& probe_push() const { return probe_push_; }

  struct Energy {
    double kinetic = 0, potential = 0, elastic = 0, debris = 0;
    double total() const { return kinetic + potential + elastic + debris; }
  };
  Energy energy() const {
    double ke = 0, pe = 0, el = 0;
#pragma omp parallel for reduction(+ : ke, pe, el) schedule(static)
    for (long i = 0; i < long(n_); ++i) {
      double v2 = 0, gx = 0;
      for (int d = 0; d < D; ++d) {
        v2 += double(v_[d][i]) * v_[d][i];
        gx += scene_.solver.gravity[d] * x_[d][i];
      }
      const double m = mass_[i];
      ke += 0.5 * m * v2;
      pe -= m * gx;
      el += m * sph::tait_energy_per_mass(rho_[i], Pd_.rho0, Pd_.B, Pd_.gamma);
    }
    return {ke, pe, el, debris_ ? debris_->energy() : 0.0};
  }
  const Energy& last_energy() const { return last_energy_; }

 private:
  void setup_params() {
    const auto& f = scene_.fluid;
    const auto& s = scene_.sph;
    h_ = s.coefh * std::sqrt(double(D)) * spacing_;
    search_ = (2 + kDriftOverH) * h_;
    const double c0 = std::sqrt(f.bulk_modulus / f.density);  // as MPM's sound speed
    Pd_.h = h_;
    Pd_.inv_h = 1 / h_;
    Pd_.support2 = 4 * h_ * h_;
    Pd_.eta2 = 0.01 * h_ * h_;
    Pd_.grad_coef = -5 * sph::wendland_alpha<D>(h_) / (h_ * h_);
    Pd_.w_alpha = sph::wendland_alpha<D>(h_);
    Pd_.rho0 = f.density;
    Pd_.gamma = f.gamma;
    Pd_.c0 = c0;
    Pd_.B = c0 * c0 * f.density / f.gamma;
    Pd_.nu = f.viscosity / f.density;
    Pd_.alpha = s.viscosity == SphViscosity::kArtificial ? s.artificial_alpha : 0.0;
    // alpha = 0 selects laminar + SPS in the pair terms; an artificial viscosity of exactly 0 means none at
    // all.
    artificial_ = s.viscosity == SphViscosity::kArtificial;
    if (artificial_ && Pd_.alpha == 0) Pd_.nu = 0;
    Pd_.ddt = s.density_diffusion * h_ * c0;
    for (int d = 0; d < D; ++d) Pd_.g[d] = scene_.solver.gravity[d];
    const double delta = spacing_;  // the study's Delta l: the particle spacing
    Pd_.sps_cs2 = (0.12 * delta) * (0.12 * delta);
    Pd_.sps_ci = 2.0 / 3.0 * 0.0066 * delta * delta;
    shifting_ = s.shifting == SphShifting::kLind;
    mdbc_ = s.boundary == SphBoundary::kMdbc;
    slip_ = s.slip == SphSlip::kNoSlip
                ? sph::Slip::kNoSlip
                : (s.slip == SphSlip::kFreeSlip ? sph::Slip::kFreeSlip : sph::Slip::kWall);
    Pd_.shift_ah = shifting_ ? s.shifting_coef * h_ : 0.0;
    Pd_.shift_tfs = s.shifting_threshold;
    Pd_.shift_dim = D;
    Pd_.shift_max = 0.1 * spacing_;  // DualSPHysics' bound: a tenth of the particle spacing per step
    P_.h = T(Pd_.h);
    P_.inv_h = T(Pd_.inv_h);
    P_.support2 = T(Pd_.support2);
    P_.eta2 = T(Pd_.eta2);
    P_.grad_coef = T(Pd_.grad_coef);
    P_.w_alpha = T(Pd_.w_alpha);
    P_.rho0 = T(Pd_.rho0);
    P_.B = T(Pd_.B);
    P_.gamma = T(Pd_.gamma);
    P_.c0 = T(Pd_.c0);
    P_.nu = T(Pd_.nu);
    P_.alpha = T(Pd_.alpha);
    P_.ddt = T(Pd_.ddt);
    for (int d = 0; d < 3; ++d) P_.g[d] = T(Pd_.g[d]);
    P_.sps_cs2 = T(Pd_.sps_cs2);
    P_.sps_ci = T(Pd_.sps_ci);
    P_.shift_ah = T(Pd_.shift_ah);
    P_.shift_tfs = T(Pd_.shift_tfs);
    P_.shift_dim = T(Pd_.shift_dim);
    P_.shift_max = T(Pd_.shift_max);
    g_norm_ = 0;
    for (int d = 0; d < D; ++d) g_norm_ += scene_.solver.gravity[d] * scene_.solver.gravity[d];
    g_norm_ = std::sqrt(g_norm_);
    for (const auto& b : scene_.boundaries)
      if (b.condition == BoundaryCondition::kSymmetry)
        for (int d = 0; d < D; ++d)
          if (std::fabs(b.shape.normal[d]) > 0.5) {
            mirror_.axis = d;
            mirror_.sign = b.shape.normal[d] > 0 ? 1 : -1;  // the normal points into the modelled water
            mirror_.at = b.shape.point[d];
          }
    Pm_ = P_;
    if (mirror_.active()) Pm_.g[mirror_.axis] = -P_.g[mirror_.axis];
  }

  void seed_fluid() {
    for (size_t k = 0; k < scene_.boundaries.size(); ++k) {
      const Boundary& b = scene_.boundaries[k];
      if (!(b.roughness > 0)) continue;
      // A basin's generated floor and quay take their roughness from basin.bed_roughness_m.
      const bool generated = scene_.basin.present && (b.name == "floor" || b.name == "quay");
      throw InputError(
          scene_.file,
          generated ? "basin.bed_roughness_m" : "boundaries." + std::to_string(k) + ".roughness_m",
          "SPH has no bed stress (boundary '" + b.name + "'): set it to 0 or run with solver.method mpm");
    }
    const Seeds seeds = seed_water<D>(scene_, spacing_, displaced_by<D>(debris_.get()), Lattice::kStretched);
    n_ = seeds.size();
    if (n_ == 0) throw InputError(scene_.file, "water", "no water to simulate");
    if (n_ > std::numeric_limits<uint32_t>::max() / 2)
      throw InputError(scene_.file, "solver.dx",
                       "too many particles for SPH's 32-bit indices: use a larger dx");
    const double rho0 = scene_.fluid.density;
    for (int d = 0; d < D; ++d) {
      x_[d].assign(seeds.x[d].begin(), seeds.x[d].end());
      v_[d].assign(n_, T(0));
    }
    rho_.resize(n_);
    mass_.resize(n_);
    vol_.resize(n_);
    for (size_t i = 0; i < n_; ++i) {
      rho_[i] = T(rho0 / (1 + seeds.strain[i]));  // rho / rho0 = 1 / J
      vol_[i] = T(seeds.volume[i]);
      mass_[i] = T(rho0 * seeds.volume[i]);
    }
    mass_total_ = water_mass(vol_, rho0);
    if (seeds.any_held) held_.assign(seeds.held.begin(), seeds.held.end());
    for (int k = 0; k < kS; ++k) tau_[k].assign(n_, T(0));
    resize_scratch(n_);
  }

  // The arrays a step fills before it reads them (the predictor's state, the rates, the shifting's sums), for
  // n particles.
  void resize_scratch(size_t n) {
    n_ = n;
    for (int d = 0; d < D; ++d) {
      xh_[d].resize(n);
      vh_[d].resize(n);
      a_[d].resize(n);
    }
    rhoh_.resize(n);
    drho_.resize(n);
    pf_.resize(n);
    irf_.resize(n);
    kf_.resize(n);
    pair_sums_.resize(n);
    visc_dt_.resize(n);
    pairs_.resize(n);
    for (int k = 0; k < kS; ++k) tau_next_[k].resize(n);
    if (shifting_) {
      for (int d = 0; d < D; ++d) gradc_[d].resize(n);
      divr_.resize(n);
    }
  }

  // --- the inflow boundary (solver/inflow.h): it moves, adds and removes particles in these arrays ---
  // SPH's density and sub-particle stress are carried along; the boundary sets a strain on the particles it
  // places, converted to their density (rho0 / (1 + e)) after each application.
  ParticleArrays<D, T> particle_arrays() {
    ParticleArrays<D, T> a;
    for (int d = 0; d < D; ++d) {
      a.x[d] = &x_[d];
      a.v[d] = &v_[d];
    }
    a.e = &strain_;
    a.vol = &vol_;
    a.held = &held_;
    a.tag = &tag_;
    a.carried = {&rho_, &mass_};
    for (auto& t : tau_) a.carried.push_back(&t);
    return a;
  }
  void seed_inflow() {
    strain_.assign(n_, T(0));
    inflow_->seed();
    after_inflow();
    mass_total_ = water_mass(vol_, scene_.fluid.density);
  }
  void apply_inflow(double t0, double t1) {
    strain_.resize(n_);  // scratch: filled here for every particle
    sph::parallel_for(n_, [&](size_t i) { strain_[i] = T(scene_.fluid.density) / rho_[i] - T(1); });
    const auto change = inflow_->apply(t0, t1);
    energy0_ += change.energy;
    after_inflow();
    if (change.structural) mass_total_ = water_mass(vol_, scene_.fluid.density);
  }
  // The buffer's particles take the density of the strain the boundary set (the recorded depth's hydrostatic
  // one); a new particle (its carried density and mass 0) takes it too, and the mass of its volume.
  void after_inflow() {
    const T rho0 = T(scene_.fluid.density);
    resize_scratch(x_[0].size());
    sph::parallel_for(n_, [&](size_t i) {
      if (tag_[i] > T(0) || rho_[i] == T(0)) rho_[i] = rho0 / (T(1) + strain_[i]);
      if (mass_[i] == T(0)) mass_[i] = T(scene_.fluid.density * double(vol_[i]));
    });
  }

  void seed_walls() {
    const int layers = static_cast<int>(std::ceil(2 * h_ / spacing_));
    sph::WallParticles w = sph::make_wall_particles(scene_, spacing_, layers, 2 * h_);
    double lo[D], hi[D];
    for (int d = 0; d < D; ++d) {
      lo[d] = scene_.domain_lo[d] - (layers + 2) * spacing_;
      hi[d] = scene_.domain_hi[d] + (layers + 2) * spacing_;
    }
    if (!grid_.init(lo, hi, kCellOverH * h_, size_t(1) << 31))
      throw InputError(scene_.file, "solver.dx",
                       "the SPH cell grid over the domain would exceed 2^31 cells: use a larger dx");
    // Slabs for the pair-once scatter (fluid_pairs): across the grid's longest axis, each as wide as the
    // largest cell distance between two particles within 2h of each other, each having drifted since its
    // sort.
    slab_axis_ = 0;
    for (int d = 1; d < D; ++d)
      if (grid_.n[d] > grid_.n[slab_axis_]) slab_axis_ = d;
    slab_w_ = static_cast<int>(std::floor((2 + 2 * kDriftOverH) * h_ * grid_.inv_size)) + 1;
    nw_ = w.size();
    // Sorted by cell once: the walls do not move.
    wall_list_.cell.resize(nw_);
    for (size_t k = 0; k < nw_; ++k) {
      T p[D];
      int c[D];
      for (int d = 0; d < D; ++d) p[d] = T(w.x[d][k]);
      if (!grid_.cell_of(p, c))
        throw InputError(scene_.file, "domain", "a wall particle lies outside the SPH grid");
      wall_list_.cell[k] = static_cast<uint32_t>(grid_.index(c));
    }
    wall_list_.build(grid_.count);
    for (int d = 0; d < D; ++d) {
      xw_[d].resize(nw_);
      vw_[d].resize(nw_);
    }
    wall_id_.resize(nw_);
    for (size_t s = 0; s < nw_; ++s) {
      const size_t k = wall_list_.order[s];
      for (int d = 0; d < D; ++d) {
        xw_[d][s] = T(w.x[d][k]);
        vw_[d][s] = T(w.velocity[3 * k + d]);
      }
      wall_id_[s] = w.wall[k];
    }
    if (mdbc_) {
      // A wall particle lies within `layers` lattice steps of open space on every axis.
      const std::vector<double> ghost =
          sph::wall_ghost_vectors(scene_, w, (layers + 1) * spacing_ * std::sqrt(D));
      for (int d = 0; d < D; ++d) gw_[d].resize(nw_);
      for (size_t s = 0; s < nw_; ++s)
        for (int d = 0; d < D; ++d) gw_[d][s] = T(ghost[3 * wall_list_.order[s] + d]);
    }
    std::vector<uint32_t> cells(nw_);
    for (size_t s = 0; s < nw_; ++s) cells[s] = wall_list_.cell[wall_list_.order[s]];
    wall_list_.cell.swap(cells);
    rhow_.assign(nw_, T(scene_.fluid.density));
    rhowh_.assign(nw_, T(scene_.fluid.density));
    drhow_.assign(nw_, T(0));
    pw_.assign(nw_, T(0));
    irw_.assign(nw_, T(1) / T(scene_.fluid.density));
    mw_ = T(scene_.fluid.density * std::pow(spacing_, D));
    mw_all_.assign(nw_, mw_);
    for (int d = 0; d < D; ++d) vwe_[d] = vw_[d];
    for (int d = 0; d < D; ++d) fw_[d].assign(nw_, T(0));
    load_impulse_.assign(scene_.boundaries.size() * D, 0.0);
    // The pressure probes sum the walls' push through their particles, which lie up to `layers` steps deep.
    probe_geometry_ = mpm::probe_geometry(scene_);
    mpm::SymmetryPlane plane;
    plane.axis = mirror_.axis;
    plane.at = mirror_.at;
    probe_faces_ = mpm::probe_faces(probe_geometry_, scene_.solver.dx, mirror_.active() ? &plane : nullptr,
                                    (layers + 0.5) * spacing_ / scene_.solver.dx);
    probe_push_.assign(scene_.instruments.pressure_probes.size(), 0.0);
    // The wall particles some probe weighs (the walls do not move): the only ones add_wall_impulses visits
    // for the probes.
    probe_walls_.clear();
    std::vector<double> weighs(probe_push_.size());
    for (size_t k = 0; k < nw_ && !weighs.empty(); ++k) {
      double x[D];
      for (int d = 0; d < D; ++d) x[d] = double(xw_[d][k]);
      bool weighed = false;
      for (int a = 0; a < D && !weighed; ++a) {  // a push along each axis alone, so that none cancels another
        double unit[D] = {};
        unit[a] = 1;
        std::fill(weighs.begin(), weighs.end(), 0.0);
        mpm::add_probe_push<D>(probe_faces_, x, unit, weighs.data());
        weighed = std::any_of(weighs.begin(), weighs.end(), [](double w) { return w != 0.0; });
      }
      if (weighed) probe_walls_.push_back(k);
    }
  }

  // The debris boxes' particles (sph/debris_particles.h), as deep as the walls', at the boxes' start poses.
  void seed_debris() {
    if (!debris_) return;
    const int layers = static_cast<int>(std::ceil(2 * h_ / spacing_));
    bodies_.seed(sph::make_debris_particles(scene_, spacing_, layers), T(scene_.fluid.density));
    bodies_.place(*debris_);
  }

  // The debris' step (sph_debris.h): their particles' densities corrected, the boxes moved by the water's
  // mid-step load and the film's, the particles placed on the boxes' new poses.
  void step_debris(double dt) {
    sph::parallel_for(bodies_.n, [&](size_t k) {
      bodies_.rho[k] =
          std::max(T(P_.rho0), sph::correct_density(bodies_.rho[k], bodies_.rhoh[k], bodies_.drho[k], T(dt)));
    });
    // The boxes take the mid-step load and the film's over the step; their particles follow.
    auto load = bodies_.loads(*debris_);
    const auto film = debris_->film(film_points());
    for (size_t b = 0; b < load.size(); ++b) load[b] += film[b];
    std::vector<BodyState> before(load.size());
    for (size_t b = 0; b < load.size(); ++b) before[b] = debris_->world().state(int(b));
    debris_->step_with_loads(load, dt);
    bodies_.place(*debris_);
    // The film stands for water under the box that the particles do not resolve: its work on the boxes is
    // energy supplied, as the hold's is.
    for (size_t b = 0; b < load.size(); ++b) {
      const BodyState after = debris_->world().state(int(b));
      energy0_ += 0.5 * dt *
                  (film[b].template head<3>().dot(before[b].velocity + after.velocity) +
                   film[b].template tail<3>().dot(before[b].angular_velocity + after.angular_velocity));
    }
  }

  // The water round the boxes for the film under a resting box (debris_coupling.h): the fluid particles
  // within a cell of a box at the mid-step, with their pressures there, in particle order.
  std::vector<CouplingNode> film_points() const {
    const double band = scene_.solver.dx;
    std::vector<int> owner(n_, -1);
    sph::parallel_for(n_, [&](size_t i) {
      double x[3] = {0, 0, 0}, nrm[3];
      for (int d = 0; d < D; ++d) x[d] = xh_[d][i];
      owner[i] = debris_->locate(x, band, nrm);
    });
    std::vector<CouplingNode> points;
    for (size_t i = 0; i < n_; ++i) {
      if (owner[i] < 0) continue;
      CouplingNode c;
      c.id = i;
      c.body = owner[i];
      for (int d = 0; d < D; ++d) c.x[d] = xh_[d][i];
      c.m = mass_[i];
      c.p = pf_[i];
      points.push_back(c);
    }
    return points;
  }

  // Orders the debris particles by cell. False (and unstable) when one has left the cell grid.
  bool sort_debris() {
    if (bodies_.n == 0) return true;
    if (bodies_.sort(grid_)) return true;
    std::ostringstream s;
    s.precision(4);
    s << "a debris box left the domain at t = " << time_ << " s (step " << steps_ << ")";
    fail(s.str());
    return false;
  }

  // Orders the fluid particles by cell. False (and unstable) when one has left the domain.
  bool sort_fluid() {
    auto& cell = fluid_list_.cell;
    cell.resize(n_);
    long outside = -1;
#pragma omp parallel for schedule(static) reduction(max : outside)
    for (long i = 0; i < long(n_); ++i) {
      T p[D];
      int c[D];
      bool in = true;
      for (int d = 0; d < D; ++d) {
        p[d] = x_[d][i];
        in &= double(p[d]) >= scene_.domain_lo[d] && double(p[d]) <= scene_.domain_hi[d];
      }
      if (in && grid_.cell_of(p, c)) {
        cell[i] = static_cast<uint32_t>(grid_.index(c));
      } else {
        cell[i] = 0;
        outside = std::max(outside, i);
      }
    }
    if (outside >= 0) {
      std::ostringstream s;
      s.precision(4);
      s << "a particle left the domain at t = " << time_ << " s (step " << steps_ << "): at (";
      for (int d = 0; d < D; ++d) s << (d ? ", " : "") << double(x_[d][outside]);
      s << ") m";
      fail(s.str());
      return false;
    }
    fluid_list_.build(grid_.count);
    if (!std::is_sorted(cell.begin(), cell.end())) {
      const auto& order = fluid_list_.order;
      auto permute = [&](std::vector<T>& a) {
        scratch_.resize(n_);
        sph::parallel_for(n_, [&](size_t i) { scratch_[i] = a[order[i]]; });
        a.swap(scratch_);
      };
      for_each_particle_array([&](std::vector<T>& a, bool optional) {
        if (!optional || !a.empty()) permute(a);
      });
      std::vector<uint32_t> sorted(n_);
      sph::parallel_for(n_, [&](size_t i) { sorted[i] = cell[order[i]]; });
      cell.swap(sorted);
    }
    return true;
  }

  double hold_lift(double t) const {
    return held_.empty() ? 0.0 : scene_.basin.forcing.hold(t) * std::fabs(scene_.solver.gravity[D - 1]);
  }

  // The rates at one state: accelerations and density rates of the fluid, density rates and forces of the
  // walls and of the debris particles (at XB, densities RB); with `shift_sums`, the shifting's grad C and div r
  // of the fluid too.
  void evaluate(const std::vector<T>* X, const std::vector<T>* V, const std::vector<T>& R, std::vector<T>& RW,
                const std::vector<T>* XB, std::vector<T>& RB, double t, bool shift_sums) {
    const sph::Params<T> P = P_;
    sph::parallel_for(n_, [&](size_t i) {
      pf_[i] = sph::tait_pressure(R[i], P);
      irf_[i] = T(1) / R[i];
      kf_[i] = sph::hydrostatic_density_slope(R[i], pf_[i], P);
    });
    const sph::NeighbourView<D, T> water = view_of(X, V, R, irf_, pf_, mass_);
    if (mdbc_) {
      // The walls' and the boxes' densities from the water at their ghost nodes, this state's; where too
      // little water lies round a ghost, the density by continuity that the step carried (DBC's).
      // With a slip mode the walls also show the water a velocity from the water's at their ghost nodes,
      // their own where the water there is too little.
      const bool slip = slip_ != sph::Slip::kWall;
      sph::parallel_for(nw_, [&](size_t k) {
        T v[D];
        const T r = ghost_density(water, xw_, gw_, k, slip, v);
        if (r > T(0)) RW[k] = r;
        if (!slip) return;
        for (int d = 0; d < D; ++d) vwe_[d][k] = r > T(0) ? v[d] : vw_[d][k];
      });
      sph::parallel_for(bodies_.n, [&](size_t k) {
        T v[D];
        const T r = ghost_density(water, XB, bodies_.g, k, false, v);
        if (r > T(0)) RB[k] = r;
      });
    }
    sph::parallel_for(nw_, [&](size_t k) {
      pw_[k] = sph::tait_pressure(RW[k], P);
      irw_[k] = T(1) / RW[k];
    });
    auto& B = bodies_;
    sph::parallel_for(B.n, [&](size_t k) {
      B.p[k] = sph::tait_pressure(RB[k], P);
      B.ir[k] = T(1) / RB[k];
    });
    const T lift = T(hold_lift(t));
    const bool sps = !artificial_;
    const sph::NeighbourView<D, T> walls = view_of(xw_, vwe_, RW, irw_, pw_, mw_all_);
    const sph::NeighbourView<D, T> boxes = view_of(XB, B.v, RB, B.ir, B.p, B.mass);
    fluid_pairs(water, walls, shift_sums, sps);
    sph::parallel_for(n_, [&](size_t a) {
      T xa[D], va[D];
      for (int d = 0; d < D; ++d) {
        xa[d] = X[d][a];
        va[d] = V[d][a];
      }
      const T rho_a = R[a], ira = irf_[a], p_a = pf_[a];
      // The sums over the boxes around the point x moving at v, and at a particle's `image` over the water and
      // the walls too (fluid_pairs holds the particle's own pairs with both).
      auto gather = [&](const sph::Params<T>& Q, const T* x, const T* v, const T* tau, bool image,
                        Accum<D, T>& A) {
        if (image)
          for_pairs(fluid_list_, X, V, x, v, [&](uint32_t b, const T* rab, T r2, const T* vab, T F) {
            sph::pair_common<D, T>(Q, rab, r2, F, vab, rho_a, ira, p_a, R[b], irf_[b], pf_[b], mass_[b], A);
            T tau_b[kS];
            for (int k = 0; k < kS; ++k) tau_b[k] = tau_[k][b];
            sph::pair_fluid_extras<D, T>(Q, rab, r2, F, vab, rho_a, kf_[a], R[b], irf_[b], mass_[b], tau,
                                         tau_b, A);
            if (shift_sums) sph::pair_shift<D, T>(rab, r2, F, mass_[b] * irf_[b], A);
          });
        auto boundary = [&](const sph::CellList& list, const sph::NeighbourView<D, T>& nv) {
          auto ranges = [&](const auto& f) { sph::for_each_neighbour_range<D>(grid_, list, x, search_, f); };
          if (shift_sums)
            sph::gather_pairs<D, T, true>(Q, nv, x, v, rho_a, ira, p_a, ranges, A);
          else
            sph::gather_pairs<D, T, false>(Q, nv, x, v, rho_a, ira, p_a, ranges, A);
        };
        if (image) boundary(wall_list_, walls);
        if (B.n > 0) boundary(B.list, boxes);
      };
      Accum<D, T> A = pair_sums_[a];
      gather(P, xa, va, nullptr, false, A);
      if (near_mirror(xa)) {  // the images across the symmetry plane, gathered at this particle's own image
        T tau_a[kS], xm[D], vm[D], tau_m[kS];
        for (int k = 0; k < kS; ++k) tau_a[k] = tau_[k][a];
        sph::reflect_point<D>(mirror_.axis, T(mirror_.at), xa, xm);
        sph::reflect_vector<D>(mirror_.axis, va, vm);
        sph::reflect_sym<D>(mirror_.axis, tau_a, tau_m);
        Accum<D, T> M;
        gather(Pm_, xm, vm, tau_m, true, M);
        sph::add_reflected(mirror_.axis, M, A);
      }
      if (shift_sums) {
        for (int d = 0; d < D; ++d) gradc_[d][a] = A.gradc[d];
        divr_[a] = A.divr;
      }
      for (int d = 0; d < D; ++d) a_[d][a] = A.acc[d] + P.g[d];
      if (!held_.empty()) a_[D - 1][a] += held_[a] * lift;  // the vacuum's hold: f(t) m |g| upward
      drho_[a] = A.drho;
      visc_dt_[a] = A.visc_dt;
      pairs_[a] = A.pairs;
      if (sps) {
        T tau[kS];
        sph::sps_stress<D, T>(P, A.gradv, rho_a, tau);
        for (int k = 0; k < kS; ++k) tau_next_[k][a] = tau[k];
      }
    });
    if (sps)
      for (int k = 0; k < kS; ++k) tau_[k].swap(tau_next_[k]);
    // Walls and debris particles: density from the fluid around them (continuity only); the pair force on
    // each, which is the opposite of what it exerts on the fluid (the pair terms are antisymmetric), for the
    // load cells and the boxes' loads. Without `direct` only the sums over the water's mirror images are added
    // to what is there (the walls: fluid_pairs holds their direct pairs).
    auto boundary_rates = [&](size_t count, const std::vector<T>* XK, const std::vector<T>* VK,
                              const std::vector<T>& RK, const std::vector<T>& irk, const std::vector<T>& pk,
                              const std::vector<T>& mass, std::vector<T>& drho_out, std::vector<T>* f_out,
                              bool direct) {
      sph::parallel_for(count, [&](size_t k) {
        T xk[D], vk[D];
        for (int d = 0; d < D; ++d) {
          xk[d] = XK[d][k];
          vk[d] = VK[d][k];
        }
        const bool image = near_mirror(xk);
        if (!direct && !image) return;
        const T rho_k = RK[k], p_k = pk[k];
        auto gather = [&](const T* x, const T* v, Accum<D, T>& A) {
          auto ranges = [&](const auto& f) {
            sph::for_each_neighbour_range<D>(grid_, fluid_list_, x, search_, f);
          };
          sph::gather_pairs<D, T, false>(P, water, x, v, rho_k, irk[k], p_k, ranges, A);
        };
        Accum<D, T> A;
        if (direct) gather(xk, vk, A);
        if (image) {
          T xm[D], vm[D];
          sph::reflect_point<D>(mirror_.axis, T(mirror_.at), xk, xm);
          sph::reflect_vector<D>(mirror_.axis, vk, vm);
          Accum<D, T> M;
          gather(xm, vm, M);
          sph::add_reflected(mirror_.axis, M, A);
        }
        if (direct) {
          drho_out[k] = A.drho;
          for (int d = 0; d < D; ++d) f_out[d][k] = mass[k] * A.acc[d];
        } else {
          drho_out[k] += A.drho;
          for (int d = 0; d < D; ++d) f_out[d][k] += mass[k] * A.acc[d];
        }
      });
    };
    if (mirror_.active()) boundary_rates(nw_, xw_, vwe_, RW, irw_, pw_, mw_all_, drhow_, fw_, false);
    boundary_rates(B.n, XB, B.v, RB, B.ir, B.p, B.mass, B.drho, B.f, true);
    long pairs = 0;
#pragma omp parallel for reduction(+ : pairs) schedule(static)
    for (long i = 0; i < long(n_); ++i) pairs += pairs_[i];
    interactions_ += pairs;
  }

  static sph::NeighbourView<D, T> view_of(const std::vector<T>* X, const std::vector<T>* V,
                                          const std::vector<T>& rho, const std::vector<T>& inv_rho,
                                          const std::vector<T>& p, const std::vector<T>& mass) {
    sph::NeighbourView<D, T> view;
    for (int d = 0; d < D; ++d) {
      view.x[d] = X[d].data();
      view.v[d] = V[d].data();
    }
    view.rho = rho.data();
    view.inv_rho = inv_rho.data();
    view.p = p.data();
    view.mass = mass.data();
    return view;
  }

  // The sums of every fluid particle over the water and the walls (acceleration, density rate, velocity
  // gradient, viscous step limit, pair count; the shifting's sums with `shift_sums`) into pair_sums_, and the
  // walls' density rates and forces from the water into drhow_ and fw_; each pair evaluated once for both
  // particles: fluid particle a takes the fluid particles b after it in cell order, each wall particle all its
  // water. Slabs of cells along the grid's longest axis, slab_w_ wide, hold particles whose neighbours lie in
  // the same slab or the next either side, so every third slab is summed at once.
  void fluid_pairs(const sph::NeighbourView<D, T>& water, const sph::NeighbourView<D, T>& walls, bool shift_sums,
                   bool sps) {
    const sph::Params<T> P = P_;
    sph::parallel_for(n_, [&](size_t i) { pair_sums_[i] = Accum<D, T>(); });
    sph::FluidView<D, T> view;
    static_cast<sph::NeighbourView<D, T>&>(view) = water;
    view.k = kf_.data();
    for (int k = 0; k < kS; ++k) view.tau[k] = tau_[k].data();
    view.sums = pair_sums_.data();
    auto pairs_after = [&](uint32_t a, auto sps_tag, auto shift_tag) {
      T xa[D], va[D];
      for (int d = 0; d < D; ++d) {
        xa[d] = water.x[d][a];
        va[d] = water.v[d][a];
      }
      // Rows of cells before a's own hold only particles before it.
      const std::size_t first_row = fluid_list_.cell[a] / std::size_t(grid_.n[0]);
      auto ranges_after_a = [&](const auto& f) {
        sph::for_each_neighbour_range<D>(
            grid_, fluid_list_, xa, search_,
            [&](uint32_t b0, uint32_t b1) {
              b0 = std::max(b0, a + 1);
              if (b0 < b1) f(b0, b1);
            },
            first_row);
      };
      Accum<D, T> A;
      sph::fluid_pairs_after<D, T, decltype(sps_tag)::value, decltype(shift_tag)::value>(P, view, a, xa, va,
                                                                                         ranges_after_a, A);
      sph::add_sums(A, pair_sums_[a]);
    };
    auto wall_pairs = [&](uint32_t k, auto shift_tag) {
      T xk[D], vk[D];
      for (int d = 0; d < D; ++d) {
        xk[d] = walls.x[d][k];
        vk[d] = walls.v[d][k];
      }
      auto ranges = [&](const auto& f) { sph::for_each_neighbour_range<D>(grid_, fluid_list_, xk, search_, f); };
      Accum<D, T> A;
      sph::gather_pairs<D, T, decltype(shift_tag)::value, true>(P, water, xk, vk, walls.rho[k], walls.inv_rho[k],
                                                                walls.p[k], ranges, A, mw_, pair_sums_.data());
      drhow_[k] = A.drho;
      for (int d = 0; d < D; ++d) fw_[d][k] = mw_ * A.acc[d];
    };
    auto pairs_in_slab = [&](int s, auto sps_tag, auto shift_tag) {
      sph::for_each_slab_range<D>(grid_, fluid_list_, slab_axis_, slab_w_, s, [&](uint32_t i0, uint32_t i1) {
        for (uint32_t a = i0; a < i1; ++a) pairs_after(a, sps_tag, shift_tag);
      });
      sph::for_each_slab_range<D>(grid_, wall_list_, slab_axis_, slab_w_, s, [&](uint32_t k0, uint32_t k1) {
        for (uint32_t k = k0; k < k1; ++k) wall_pairs(k, shift_tag);
      });
    };
    using Yes = std::true_type;
    using No = std::false_type;
    const int slabs = (grid_.n[slab_axis_] + slab_w_ - 1) / slab_w_;
    sph::coloured_for(slabs, 3, [&](int s) {
      if (sps && shift_sums) pairs_in_slab(s, Yes{}, Yes{});
      if (sps && !shift_sums) pairs_in_slab(s, Yes{}, No{});
      if (!sps && shift_sums) pairs_in_slab(s, No{}, Yes{});
      if (!sps && !shift_sums) pairs_in_slab(s, No{}, No{});
    });
  }

  // mDBC: the density of boundary particle k (positions XK, ghost vectors GK) from the water (with the masses
  // and the 1/rho this evaluation computed) round its ghost node, and round the node's image across a
  // symmetry plane; 0 where that water is too little (sph::ghost_density). With `slip`, also the velocity the
  // particle shows the water in the slip mode (into v; where the density is not 0).
  T ghost_density(const sph::NeighbourView<D, T>& water, const std::vector<T>* XK, const std::vector<T>* GK,
                  size_t k, bool slip, T* v) const {
    T g[D], gv[D];
    for (int d = 0; d < D; ++d) {
      gv[d] = GK[d][k];
      g[d] = XK[d][k] + gv[d];
    }
    auto gather = [&](const T* at, sph::GhostSums<D, T>& S) {
      auto ranges = [&](const auto& f) {
        sph::for_each_neighbour_range<D>(grid_, fluid_list_, at, search_, f);
      };
      if (slip)
        sph::gather_ghost<D, T, true>(P_, water, at, ranges, S);
      else
        sph::gather_ghost<D, T, false>(P_, water, at, ranges, S);
    };
    sph::GhostSums<D, T> S;
    gather(g, S);
    if (near_mirror(g)) {
      T gm[D];
      sph::reflect_point<D>(mirror_.axis, T(mirror_.at), g, gm);
      sph::GhostSums<D, T> M;
      gather(gm, M);
      sph::add_reflected_ghost(mirror_.axis, M, S);
    }
    const T rho = sph::ghost_density<D, T>(S, gv, P_.rho0);
    if (slip && rho > T(0)) {
      T vw[D];
      for (int d = 0; d < D; ++d) vw[d] = vw_[d][k];
      sph::ghost_slip_velocity<D, T>(slip_, S, gv, vw, v);
    }
    return rho;
  }

  // Particle shifting after the corrector, from the mid-step sums and speed (DualSPHysics adds it to the
  // corrector's displacement). The cells are re-sorted at the next step's start, so the search margin holds.
  void shift(T dt) {
    const sph::Params<T> P = P_;
    sph::parallel_for(n_, [&](size_t i) {
      T gc[D], dr[D], s2 = 0;
      for (int d = 0; d < D; ++d) {
        gc[d] = gradc_[d][i];
        s2 += vh_[d][i] * vh_[d][i];
      }
      sph::shift_displacement<D, T>(P, gc, divr_[i], std::sqrt(s2), dt, dr);
      for (int d = 0; d < D; ++d) x_[d][i] += dr[d];
    });
  }

  // Whether the kernel's support (with the drift margin) around x reaches across the symmetry plane.
  bool near_mirror(const T* x) const { return mirror_.active() && mirror_.side(x) < search_; }

  // A particle that crossed the symmetry plane is its image that crossed the other way: it takes the image's
  // place (position and velocity reflected), as the whole flow would have it.
  void reflect_crossings() {
    const int ax = mirror_.axis;
    const T at = T(mirror_.at);
    sph::parallel_for(n_, [&](size_t i) {
      T x[D];
      for (int d = 0; d < D; ++d) x[d] = x_[d][i];
      if (mirror_.side(x) >= 0) return;
      x_[ax][i] = T(2) * at - x_[ax][i];
      v_[ax][i] = -v_[ax][i];
    });
  }

  // Calls body(b, r_ab, r^2, v_ab, F) for every particle b of `list` (positions X, velocities V) within the
  // kernel's support of the point xa moving at va, F the kernel gradient's factor; with `first`, only the
  // particles from that one on in cell order. A particle at xa itself (the particle whose neighbours these
  // are) is left out: its terms are all zero.
  template <class Body>
  void for_pairs(const sph::CellList& list, const std::vector<T>* X, const std::vector<T>* V, const T* xa,
                 const T* va, const Body& body, uint32_t first = 0) const {
    sph::for_each_neighbour_range<D>(grid_, list, xa, search_, [&](uint32_t b0, uint32_t b1) {
      for (uint32_t b = std::max(b0, first); b < b1; ++b) {
        T rab[D], r2 = 0;
        for (int d = 0; d < D; ++d) {
          rab[d] = xa[d] - X[d][b];
          r2 += rab[d] * rab[d];
        }
        if (r2 >= P_.support2 || r2 == T(0)) continue;
        T vab[D];
        for (int d = 0; d < D; ++d) vab[d] = va[d] - V[d][b];
        body(b, rab, r2, vab, sph::wendland_gradient_factor(r2, P_));
      }
    });
  }

  // DualSPHysics' step condition from the rates just evaluated, bounded by the scene's max_dt and by the
  // cells' drift margin.
  double step_size() {
    const double amax = std::sqrt(sph::parallel_max<double>(n_, [&](size_t i) {
      double s = 0;
      for (int d = 0; d < D; ++d) s += double(a_[d][i]) * a_[d][i];
      return s;
    }));
    const double vdt = sph::parallel_max<double>(n_, [&](size_t i) { return double(visc_dt_[i]); });
    update_max_speed();
    // The boxes' particles must not drift past the search's margin either.
    const double body_speed = std::sqrt(bodies_.max_speed2());
    const double dt_f = amax > 0 ? std::sqrt(h_ / amax) : 1e300;
    const double dt_cv = h_ / (Pd_.c0 + h_ * vdt);
    double dt = scene_.sph.cfl * std::min(dt_f, dt_cv);
    dt = std::min(dt, scene_.solver.max_dt);
    if (max_speed_ > 0) dt = std::min(dt, kDriftOverH * h_ / max_speed_);
    if (body_speed > 0) dt = std::min(dt, kDriftOverH * h_ / body_speed);
    return dt;
  }

  void update_max_speed() {
    max_speed_ = std::sqrt(sph::parallel_max<double>(n_, [&](size_t i) {
      double s = 0;
      for (int d = 0; d < D; ++d) s += double(v_[d][i]) * v_[d][i];
      return s;
    }));
  }

  void add_wall_impulses(double dt) {
    if (!probe_push_.empty()) {  // the push on the water is minus the water's force on the wall's particles
      std::fill(probe_push_.begin(), probe_push_.end(), 0.0);
      for (const size_t k : probe_walls_) {
        double x[D], push[D];
        bool pushed = false;
        for (int d = 0; d < D; ++d) {
          x[d] = double(xw_[d][k]);
          push[d] = -double(fw_[d][k]) * dt;
          pushed = pushed || push[d] != 0.0;
        }
        if (pushed) mpm::add_probe_push<D>(probe_faces_, x, push, probe_push_.data());
      }
    }
    if (scene_.instruments.loads.empty()) return;
    for (size_t k = 0; k < nw_; ++k) {
      if (wall_id_[k] < 0) continue;
      for (int d = 0; d < D; ++d) load_impulse_[wall_id_[k] * D + d] += double(fw_[d][k]) * dt;
    }
  }

  // NaN, or energy beyond what the start and the hold supplied: the step blew up.
  void audit(double dt) {
    bool finite = true;
#pragma omp parallel for reduction(&& : finite) schedule(static)
    for (long i = 0; i < long(n_); ++i) {
      bool f = std::isfinite(double(rho_[i]));
      for (int d = 0; d < D; ++d) f = f && std::isfinite(double(x_[d][i])) && std::isfinite(double(v_[d][i]));
      finite = finite && f;
    }
    std::ostringstream s;
    s.precision(4);
    if (!finite) {
      s << "NaN or Inf in the particles at t = " << time_ << " s (step " << steps_ << ", dt = " << dt
        << " s)";
      fail(s.str());
      return;
    }
    last_energy_ = energy();
    const double e = last_energy_.total();
    if (e > energy0_ + energy_slack_) {
      s << "energy grew beyond what gravity and forcing supply at t = " << time_ << " s (step " << steps_
        << "): total " << e << " J against " << energy0_ << " J initially (max speed " << max_speed_
        << " m/s)";
      fail(s.str());
    }
  }

  void fail(const std::string& what) {
    status_ = RunStatus::kUnstable;
    message_ = what;
  }

  const Scene& scene_;
  InstrumentSet<SphSolver> instruments_;
  sph::Params<T> P_;
  sph::Params<double> Pd_;
  sph::Mirror mirror_;  // the symmetry plane, if the scene has one
  sph::Params<T> Pm_;   // P_ in the reflected frame (gravity reflected)
  bool artificial_ = false;
  bool shifting_ = false;
  bool mdbc_ = false;  // walls and boxes by mDBC (ghost nodes) rather than DBC (continuity)
  sph::Slip slip_ = sph::Slip::kWall;  // mDBC's slip mode for the walls
  double spacing_ = 0, h_ = 0, search_ = 0, g_norm_ = 0;
  sph::CellGrid<D> grid_;
  sph::CellList fluid_list_, wall_list_;
  int slab_axis_ = 0, slab_w_ = 1;  // fluid_pairs' slabs of cells

  // Fluid: state at t, the predictor's state at t + dt/2, the rates of the last evaluation.
  size_t n_ = 0;
  std::vector<T> x_[D], v_[D], rho_, mass_, vol_, held_;
  std::vector<T> tag_, strain_;  // inflow only: buffer (1) or free water (0); the strain the boundary sets
  std::vector<T> xh_[D], vh_[D], rhoh_;
  std::vector<T> a_[D], drho_, pf_, irf_, kf_,
      visc_dt_;                  // pressure, 1/rho, d rho / d p of the state last evaluated
  std::vector<Accum<D, T>> pair_sums_;  // the fluid-fluid pairs' sums of the evaluation under way
  std::vector<int> pairs_;
  std::vector<T> tau_[kS], tau_next_[kS];  // sub-particle stress over rho^2, from the previous evaluation
  std::vector<T> gradc_[D], divr_;         // the shifting's sums at the last mid-step (shifting only)
  std::vector<T> scratch_;
  double mass_total_ = 0;

  // Walls: fixed positions and prescribed velocities, density at t and t + dt/2, its rate, pressure, pair
  // force.
  size_t nw_ = 0;
  std::vector<T> vwe_[D];  // the velocity each wall particle shows the water: vw_, or its slip mode's
  std::vector<T> xw_[D], vw_[D], rhow_, rhowh_, drhow_, pw_, irw_, fw_[D];
  std::vector<T> gw_[D];  // mDBC: from each wall particle to its ghost node
  std::vector<int> wall_id_;
  T mw_ = 0;
  std::vector<T> mw_all_;  // mw_ per wall particle, for the gathers' views

  // Debris: the boxes (Bullet) and their boundary particles; empty without debris.
  std::unique_ptr<DebrisCoupling> debris_;
  std::unique_ptr<InflowBoundary<D, T>> inflow_;
  sph::SphDebris<D, T> bodies_;
  std::vector<double> load_impulse_;
  std::vector<double> probe_geometry_;  // the pressure probes' points and normals (mpm::probe_geometry)
  mpm::ProbeFaces probe_faces_;         // a view of them
  std::vector<double> probe_push_;      // per probe: this step's push through the wall particles
  std::vector<size_t> probe_walls_;     // the wall particles within some probe's reach

  double time_ = 0, dt_ = 0, max_speed_ = 0;
  long steps_ = 0, interactions_ = 0;
  double energy0_ = 0, energy_slack_ = 0;
  Energy last_energy_;
  RunStatus status_ = RunStatus::kRunning;
  std::string message_;
};

}  // namespace

// This copy's factory (solver/cpu_kernels.h).
std::unique_ptr<Simulation> FLUME_KERNELS_ENTRY(make_sph_simulation)(const Scene& scene, const SimulationOptions& options) {
  const bool f = scene.solver.precision == Precision::kFloat;
  if (scene.dimension == 2) {
    if (f) return std::make_unique<SphSolver<2, float>>(scene, options);
    return std::make_unique<SphSolver<2, double>>(scene, options);
  }
  if (f) return std::make_unique<SphSolver<3, float>>(scene, options);
  return std::make_unique<SphSolver<3, double>>(scene, options);
}

}  // namespace flume
