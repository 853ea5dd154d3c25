// A run's clock, step-size control, energy audit and status, for both backends (MpmSolver, MpmCuda): the
// bookkeeping around the stages, written once so the backends cannot drift apart in it. Host code.
#pragma once
#include <algorithm>
#include <string>
#include <vector>

#include "solver/checkpoint.h"
#include "solver/mpm/audit.h"
#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume::mpm {

// The energies the audit sums (J).
struct Energy {
  double kinetic = 0, potential = 0, elastic = 0;
  double debris = 0;  // the boxes' kinetic and potential energy
  double total() const { return kinetic + potential + elastic + debris; }
};

struct RunState {
  double time = 0, dt = 0, max_speed = 0;
  long steps = 0;
  double mass = 0;  // rho times the particles' volumes summed in double
  double energy0 = 0, energy_slack = 0;  // the audit's budget: the total may not exceed energy0 + slack
  Energy last_energy;
  RunStatus status = RunStatus::kRunning;
  std::string message;

  // The audit's budget at the start: the initial total and its slack (mpm::energy_slack; an inflow's scale
  // when it feeds more, `inflow_scale`, 0 without one).
  void start_audit(const Scene& scene, const Energy& e, double inflow_scale) {
    energy0 = e.total();
    energy_slack = std::max(mpm::energy_slack(scene, mass, e.kinetic), inflow_scale);
  }
  // After a velocity field is imposed (Simulation::set_rigid_velocity): the new total is the budget.
  void restart_audit(const Energy& e) {
    energy0 = e.total();
    energy_slack = std::max(energy_slack, 0.01 * e.kinetic);
  }

  // The next step's size (CFL on sound speed c plus the fastest particle, capped by max_dt, cut to land on the
  // end time); 0 when the run has reached its end (the status is then kOk).
  double next_dt(const Scene& scene, double dx, double c) {
    double h = std::min(scene.solver.max_dt, scene.solver.cfl * dx / (c + max_speed));
    const double remaining = scene.solver.end_time - time;
    if (h >= remaining) h = remaining;
    if (!(h > 0)) {
      status = RunStatus::kOk;
      return 0;
    }
    return h;
  }

  // The end of a step of size h, after the stages: the clock, the inflow where there is one (`apply_inflow(t0,
  // t1)`), then the instruments (all of them when the step went unstable, as its last record).
  template <class Instruments, class Solver, class ApplyInflow>
  RunStatus end_step(const Scene& scene, double h, bool has_inflow, const ApplyInflow& apply_inflow,
                     Instruments& instruments, const Solver& solver, const std::vector<double>& load_impulse) {
    time += h;
    dt = h;
    ++steps;
    if (has_inflow && status == RunStatus::kRunning) apply_inflow(time - h, time);
    if (status == RunStatus::kUnstable) {
      instruments.sample(solver, time, h, true);
      return status;
    }
    instruments.add_impulses(load_impulse, h);
    instruments.sample(solver, time, h, false);
    if (time >= scene.solver.end_time - 1e-12) status = RunStatus::kOk;
    return status;
  }

  void fail(const std::string& what) {
    status = RunStatus::kUnstable;
    message = what;
  }

  // Written and read by the backends' checkpoints. A loaded unstable run is refused; a finished run resumed to
  // a later end time runs on.
  void checkpoint(StateArchive& ar, const Scene& scene) {
    ar.fields(time, dt, max_speed, steps, energy0, energy_slack, last_energy, mass, status, message);
    if (!ar.loading()) return;
    if (status == RunStatus::kUnstable) ar.fail("status", "the checkpointed run had gone unstable");
    status = time < scene.solver.end_time - 1e-12 ? RunStatus::kRunning : RunStatus::kOk;
  }
};

// A loaded checkpoint's particle arrays must all hold n particles (held and tag may be empty); host or device
// arrays.
template <int D, class Array>
bool particle_lengths_agree(size_t n, const Array* x, const Array* v, const Array* C, const Array& e,
                            const Array& vol, const Array& held, const Array& tag) {
  const auto bad = [&](const Array& a) { return a.size() != n; };
  bool mismatch = bad(e) || bad(vol) || (!held.empty() && bad(held)) || (!tag.empty() && bad(tag));
  for (int d = 0; d < D; ++d) mismatch = mismatch || bad(x[d]) || bad(v[d]);
  for (int k = 0; k < D * D; ++k) mismatch = mismatch || bad(C[k]);
  return !mismatch;
}

}  // namespace flume::mpm
