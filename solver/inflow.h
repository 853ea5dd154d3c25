// The inflow boundary (issue 3, `waseda_apron`): water enters through the vertical plane x = x_in with the
// depth h(t, y) and depth-averaged streamwise velocity u(t, y) that a section instrument of another run
// recorded there (solver/instruments.h, /sections/<name> in its result.h5).
//
// How. Upstream of the plane lies a kinematic buffer, `buffer_cells` cells long (the quadratic stencil's
// reach and more, so the water just past the plane sees a full water column behind it): a lattice at the
// run's particle spacing s whose lines along x (one per layer r and row across) each translate downstream by
// phi(t) = integral of u(z_r) dt, the recorded velocity of their layer (the section's profile; the depth
// average where the record has none). Every buffer particle moves at that velocity with the hydrostatic
// strain of the recorded depth, so the buffer pushes on the water downstream with the recorded pressure.
// After each step the buffer is put back on its lattice; a slot whose position passes x_in becomes free water
// when its layer is wet, the top layer's wet fraction error-diffused along its line, so the mass injected
// follows the recorded flux rho integral(u dz) dt to within one particle per line, whatever the rounding of h
// / s.
//
// Backflow. Free water that crosses the plane upstream is removed (counted as absorbed): the record already
// holds the flux the full run sent back through this plane (the reflection from the quay wall included), so
// water this run sends back leaves as it did there, instead of piling up against a wall that was not there.
// The buffer imposes both h and u, which is right for a replay of the same flow and reflects only the
// difference between this run and the recorded one.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "solver/instruments.h"
#include "solver/mpm_kernels.h"
#include "solver/scene.h"

namespace flume {

// Reads scene.inflow.record's /sections/<section> into scene.inflow (time, y, depth, velocity) and checks it
// against the scene. Throws InputError naming the scene file, the field and what is allowed.
void load_inflow_record(Scene& scene);

struct InflowSample {
  double depth = 0, velocity = 0;
};
// The record at time t and lateral position y: linear in time, clamped to the record's ends; across y the bin
// that holds y (bins partition the width, so the flux is kept); a 2D record drives every y alike.
InflowSample inflow_at(const InflowSettings& f, double t, double y);
// The streamwise velocity `height_m` above the floor: the record's layer there when it has a profile, else
// the depth average.
double inflow_velocity_at(const InflowSettings& f, double t, double y, double height_m);

// Strain e = J - 1 of water at rest under `head_m` of water: the inverse of the Tait law (as the solver seeds
// it).
inline double hydrostatic_strain_at(double head_m, const FluidSettings& fluid, double g) {
  const double p = fluid.density * g * std::max(0.0, head_m);
  return std::expm1(-std::log1p(fluid.gamma * p / fluid.bulk_modulus) / fluid.gamma);
}

// The solver's particle arrays, as the inflow adds, moves and removes particles in them. `held` may be empty;
// `tag` is 1 for buffer particles and 0 for free water; `vol` is the reference volume (mass / rho); `e` the
// strain J - 1 the boundary sets on the particles it places (SPH keeps a density instead and converts). `C`
// (MPM's affine velocity, zeroed where a particle is placed) may be null (SPH). `carried`: the solver's other
// per-particle arrays, which the boundary only keeps in step: removed with their particles, 0 for new ones.
template <int D, typename T>
struct ParticleArrays {
  std::vector<T>* x[D];
  std::vector<T>* v[D];
  std::vector<T>* C[D * D] = {};
  std::vector<T>* e;
  std::vector<T>* vol;
  std::vector<T>* held;
  std::vector<T>* tag;
  std::vector<std::vector<T>*> carried;
  size_t size() const { return x[0]->size(); }
};

template <int D, typename T>
class InflowBoundary {
 public:
  struct Change {
    bool structural = false;  // particles were added or removed: the solver must re-sort
    double energy = 0;        // energy of the particles it set, added and removed: after minus before (J)
  };

  InflowBoundary(const Scene& scene, double spacing, ParticleArrays<D, T> a)
      : f_(scene.inflow), fluid_(scene.fluid), law_(scene.fluid.bulk_modulus, scene.fluid.gamma), a_(a), s_(spacing) {
    x_in_ = f_.x_m;
    lb_ = f_.buffer_cells * scene.solver.dx;
    // The floor under the plane's middle: at its edge (y_lo) a side wall's box would count as the ground.
    Vec3d at{};
    at[0] = x_in_;
    if constexpr (D == 3) at[1] = 0.5 * (f_.y_lo + f_.y_hi);
    floor_ = ground_level(scene, at);
    for (int d = 0; d < D; ++d) g_[d] = scene.solver.gravity[d];
    g_up_ = std::fabs(scene.solver.gravity[D - 1]);
    if constexpr (D == 3) {
      across_ = std::max(1L, std::lround((f_.y_hi - f_.y_lo) / s_));
      sy_ = (f_.y_hi - f_.y_lo) / across_;
    }
    // The lattice's volume per slot: s along x and z, and across y the width over the lines (s^2 in 2D).
    v0_ = D == 3 ? s_ * s_ * sy_ : s_ * s_;
    double h_max = 0;
    for (double h : f_.depth) h_max = std::max(h_max, h);
    layers_ = static_cast<long>(std::ceil(h_max / s_)) + 1;
    width_ = static_cast<long>(std::ceil(lb_ / s_)) + 4;
    const size_t lines = static_cast<size_t>(across_ * layers_);
    phi_.assign(lines, 0.0);
    carry_.assign(lines, 0.0);
    a_.tag->assign(a_.size(), T(0));
  }

  // The buffer at t = 0.
  void seed() { apply(0.0, 0.0); }

  // After the step from t0 to t1: advances each lattice line by its recorded velocity, turns the particles
  // that passed x_in into free water, removes free water upstream of x_in, and puts every buffer particle
  // back on its slot. A slot of layer r holds water where the layer is wet: in the buffer where (r + 1/2) s
  // lies below the recorded depth h; as it crosses, with the layer's wet fraction h / s - r error-diffused
  // along the line, so the flux is integral of u(z) over the depth to within a particle per line.
  Change apply(double t0, double t1) {
    const double dt = t1 - t0;
    Change out;
    double e_before = 0, e_after = 0;
    const size_t lines = phi_.size();
    std::vector<double> phi_new(lines), u_new(lines), h_new(across_);
    std::vector<long> first(lines);
    need_.assign(lines * width_, 0);
    have_.assign(lines * width_, 0);
    std::vector<double> u_mid(layers_), u_end(layers_);
    for (long k = 0; k < across_; ++k) {
      const double y = y_of(k);
      h_new[k] = inflow_at(f_, t1, y).depth;
      profile(0.5 * (t0 + t1), y, u_mid);
      profile(t1, y, u_end);
      for (long r = 0; r < layers_; ++r) {
        const size_t L = k * layers_ + r;
        const double z = (r + 0.5) * s_;
        phi_new[L] = phi_[L] + u_mid[r] * dt;
        u_new[L] = u_end[r];
        const long c_lo = col_floor(phi_[L]) + 1, c_hi = col_floor(phi_new[L]);  // crossing x_in this step
        const long b_lo = c_hi + 1, b_hi = col_floor(phi_new[L] + lb_);          // the buffer after it
        first[L] = std::min(c_lo, b_lo);
        char* need = &need_[L * width_];
        for (long c = c_lo; c <= c_hi && c - first[L] < width_; ++c) {
          carry_[L] += std::clamp(h_new[k] / s_ - r, 0.0, 1.0);
          if (carry_[L] >= 0.5) {
            carry_[L] -= 1;
            need[c - first[L]] = 1;
          }
        }
        const bool wet = z < h_new[k];
        for (long c = b_lo; c <= b_hi && c - first[L] < width_; ++c) need[c - first[L]] = wet;
      }
    }
    // Existing particles: buffer particles back to their slots (or removed), free water upstream removed. The
    // few that concern the boundary are found by the threads (in index order), then handled in that order.
    const size_t n = a_.size();
    std::vector<char> remove(n, 0);
    size_t removed = 0;
    for (const size_t i : boundary_particles()) {
      const bool buffer = (*a_.tag)[i] > T(0);
      const double x = (*a_.x[0])[i];
      e_before += energy(i);
      if (!buffer) {
        remove[i] = 1;
        ++removed;
        absorbed_ += mass(i);
        continue;
      }
      const long k =
          D == 3 ? std::clamp(std::lround(((*a_.x[1])[i] - f_.y_lo) / sy_ - 0.5), 0L, across_ - 1) : 0;
      const long r = std::lround(((*a_.x[D - 1])[i] - floor_) / s_ - 0.5);
      const size_t L = k * layers_ + std::clamp(r, 0L, layers_ - 1);
      const long j = std::lround((x_in_ + phi_[L] - x) / s_ - 0.5) - first[L];
      const size_t slot = L * width_ + j;
      if (r < 0 || r >= layers_ || j < 0 || j >= width_ || !need_[slot] || have_[slot]) {
        remove[i] = 1;  // off the lattice: out at the buffer's back (u < 0), or a layer that is dry now
        ++removed;
        continue;
      }
      have_[slot] = 1;
      place(i, k, r, first[L] + j, phi_new[L], u_new[L], h_new[k]);
      e_after += energy(i);
    }
    if (removed) compact(remove);
    // Missing slots: new particles.
    size_t added = 0;
    for (size_t L = 0; L < lines; ++L)
      for (long j = 0; j < width_; ++j) {
        const size_t slot = L * width_ + j;
        if (!need_[slot] || have_[slot]) continue;
        const size_t i = a_.size();
        for (int d = 0; d < D; ++d) {
          a_.x[d]->push_back(T(0));
          a_.v[d]->push_back(T(0));
        }
        for (int q = 0; q < D * D; ++q)
          if (a_.C[q]) a_.C[q]->push_back(T(0));
        for (auto* c : a_.carried) c->push_back(T(0));
        a_.e->push_back(T(0));
        a_.vol->push_back(T(v0_));
        if (!a_.held->empty()) a_.held->push_back(T(0));
        a_.tag->push_back(T(1));
        const long k = static_cast<long>(L) / layers_;
        place(i, k, static_cast<long>(L) % layers_, first[L] + j, phi_new[L], u_new[L], h_new[k]);
        e_after += energy(i);
        ++added;
      }
    phi_ = phi_new;
    out.structural = removed > 0 || added > 0;
    out.energy = e_after - e_before;
    return out;
  }

  // The lattice lines' advance and error carries, and the masses in and out (solver/checkpoint.h).
  void checkpoint(StateArchive& ar) {
    ar.section("inflow");
    ar.expect("inflow lines", phi_.size());
    ar(phi_);
    ar(carry_);
    ar(injected_);
    ar(absorbed_);
  }

  double injected_mass() const { return injected_; }  // kg (kg/m in 2D) that entered through x_in
  double absorbed_mass() const { return absorbed_; }  // kg that left upstream through x_in
  // An energy scale for the solver's audit: 1% of the potential energy of the recorded inflow's volume
  // lifted by the largest depth.
  double energy_scale() const {
    double h = 0, q = 0;
    for (size_t i = 0; i < f_.depth.size(); ++i) {
      h = std::max(h, f_.depth[i]);
      q += f_.depth[i] * std::fabs(f_.velocity[i]);
    }
    const double width = D == 3 ? f_.y_hi - f_.y_lo : 1.0;
    const double duration = f_.time.back() - f_.time.front();
    const double volume = q / double(f_.depth.size()) * duration * width;
    return 0.01 * fluid_.density * volume * g_up_ * std::max(h, s_);
  }

 private:
  // The velocity of each layer at (t, y): the recorded profile, shifted by the same amount in every layer so
  // that its flux over the wet layers, sum of u_r s min(1, max(0, h / s - r)), is the recorded h u. The
  // profile gives the shear (and the momentum over the quay); the depth and mean velocity give the mass,
  // exactly.
  void profile(double t, double y, std::vector<double>& u) const {
    const InflowSample m = inflow_at(f_, t, y);
    double flux = 0;
    for (long r = 0; r < layers_; ++r) {
      u[r] = inflow_velocity_at(f_, t, y, (r + 0.5) * s_);
      flux += u[r] * s_ * std::clamp(m.depth / s_ - r, 0.0, 1.0);
    }
    const double shift = m.depth > 0 ? (m.depth * m.velocity - flux) / m.depth : 0.0;
    for (long r = 0; r < layers_; ++r) u[r] += shift;
  }

  // The buffer particles and the free water upstream of x_in, in index order: each of a fixed number of
  // chunks filtered by one thread, then joined in chunk order.
  const std::vector<size_t>& boundary_particles() {
    const size_t n = a_.size();
    constexpr long kChunks = 64;
    chunk_.resize(kChunks);
    const std::vector<T>& tag = *a_.tag;
    const std::vector<T>& x0 = *a_.x[0];
#pragma omp parallel for schedule(dynamic)
    for (long c = 0; c < kChunks; ++c) {
      std::vector<size_t>& out = chunk_[c];
      out.clear();
      for (size_t i = n * c / kChunks; i < n * (c + 1) / kChunks; ++i)
        if (tag[i] > T(0) || !(double(x0[i]) >= x_in_)) out.push_back(i);
    }
    boundary_.clear();
    for (const auto& part : chunk_) boundary_.insert(boundary_.end(), part.begin(), part.end());
    return boundary_;
  }

  // Slot c of a line lies at x_in + phi - (c + 1/2) s: this is the largest c at or past x_in.
  long col_floor(double phi) const { return static_cast<long>(std::floor(phi / s_ - 0.5)); }
  double y_of(long k) const { return D == 3 ? f_.y_lo + (k + 0.5) * sy_ : 0.0; }

  void place(size_t i, long k, long r, long c, double phi, double u, double h) {
    const double x = x_in_ + phi - (c + 0.5) * s_, z = floor_ + (r + 0.5) * s_;
    (*a_.x[0])[i] = T(x);
    (*a_.x[D - 1])[i] = T(z);
    if constexpr (D == 3) (*a_.x[1])[i] = T(y_of(k));
    for (int d = 0; d < D; ++d) (*a_.v[d])[i] = T(d == 0 ? u : 0.0);
    for (int q = 0; q < D * D; ++q)
      if (a_.C[q]) (*a_.C[q])[i] = T(0);
    (*a_.e)[i] = T(hydrostatic_strain_at(h - (z - floor_), fluid_, g_up_));
    if (x >= x_in_) {  // it crossed: free water from now on
      (*a_.tag)[i] = T(0);
      injected_ += mass(i);
    } else {
      (*a_.tag)[i] = T(1);
    }
  }

  double mass(size_t i) const { return fluid_.density * double((*a_.vol)[i]); }
  double energy(size_t i) const {
    double v2 = 0, gx = 0;
    for (int d = 0; d < D; ++d) {
      v2 += double((*a_.v[d])[i]) * double((*a_.v[d])[i]);
      gx += g_[d] * double((*a_.x[d])[i]);
    }
    const double m = mass(i), V = (*a_.vol)[i];
    return 0.5 * m * v2 - m * gx + V * law_.energy_density(double((*a_.e)[i]));
  }

  void compact(const std::vector<char>& remove) {
    std::vector<std::vector<T>*> arrays;
    for (int d = 0; d < D; ++d) {
      arrays.push_back(a_.x[d]);
      arrays.push_back(a_.v[d]);
    }
    for (int q = 0; q < D * D; ++q)
      if (a_.C[q]) arrays.push_back(a_.C[q]);
    for (auto* c : a_.carried) arrays.push_back(c);
    arrays.push_back(a_.e);
    arrays.push_back(a_.vol);
    if (!a_.held->empty()) arrays.push_back(a_.held);
    arrays.push_back(a_.tag);
#pragma omp parallel for schedule(dynamic)
    for (long k = 0; k < long(arrays.size()); ++k) {  // each array squeezed by one thread
      std::vector<T>& a = *arrays[k];
      size_t w = 0;
      for (size_t i = 0; i < a.size(); ++i)
        if (!remove[i]) a[w++] = a[i];
      a.resize(w);
    }
  }

  const InflowSettings& f_;
  FluidSettings fluid_;
  mpm::TaitLaw<double> law_;  // for the energy of the particles the boundary sets
  ParticleArrays<D, T> a_;
  double s_, v0_ = 0, x_in_ = 0, lb_ = 0, floor_ = 0, g_up_ = 0, sy_ = 1;
  double g_[D] = {};
  long across_ = 1, layers_ = 1, width_ = 1;  // lattice lines across y and up z; slots per line
  std::vector<double> phi_, carry_;           // per line k * layers_ + r: phase (m) and the error diffusion
  std::vector<char> need_, have_;             // per line and slot, this step
  std::vector<std::vector<size_t>> chunk_;    // boundary_particles' work
  std::vector<size_t> boundary_;
  double injected_ = 0, absorbed_ = 0;
};

}  // namespace flume
