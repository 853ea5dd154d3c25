// Debris instruments: each body's trajectory at the solver's rate and resampled at the experiment's
// accelerometer rate (30 Hz), with the accelerometer force m*a at both rates. Plain arrays, ready to be written
// as /debris/<name>/{solver,resampled}/<field> (n x 3 or n x 4 doubles, contiguous).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "solver/rigid/rigid_world.h"

namespace flume {

struct DebrisSeries {
  std::vector<double> time;                          // s
  std::vector<std::array<double, 3>> position;       // centre of mass, m
  std::vector<std::array<double, 4>> orientation;    // quaternion body -> world (w, x, y, z)
  std::vector<std::array<double, 3>> velocity;       // m/s
  std::vector<std::array<double, 3>> angular_velocity;  // rad/s, world frame
  // Solver rate: mean acceleration since the previous stored sample. Resampled: mean over the sample period
  // centred on the sample time (see DebrisRecorder). World frame, m/s^2.
  std::vector<std::array<double, 3>> acceleration;
  std::vector<std::array<double, 3>> force;          // accelerometer force m * acceleration, N
  // What a strapped-down accelerometer reads: R^T (a - g), body frame, m/s^2 (+g upward at rest).
  std::vector<std::array<double, 3>> specific_force_body;
  size_t size() const { return time.size(); }
};

class StateArchive;
void checkpoint_state(StateArchive& ar, DebrisSeries& s);

// Call record() once before the first step (initial state) and after every RigidWorld::step(); finish() at the
// end. The resampled series has samples at t_k = k / resample_hz: position by cubic Hermite interpolation
// between the recorded states (exact for constant acceleration), orientation by slerp, velocities linearly,
// and the acceleration as the mean over [t_k - T/2, t_k + T/2] with T = 1 / resample_hz, i.e.
// (v(t_k + T/2) - v(t_k - T/2)) / T: an accelerometer's anti-aliasing average, without the half-period delay a
// trailing average would add. A sample is therefore complete T/2 after t_k; finish() closes the last one with
// a shortened window. The first sample's window starts at the first record.
class DebrisRecorder {
 public:
  // solver_rate_hz = 0 stores every record() call; a positive value keeps a solver-rate sample only when at
  // least 1/solver_rate_hz has passed since the last one kept (memory: a 20 s run at dt = 1e-5 is 2e6 samples
  // per body), the acceleration then being the mean over that interval. The resampled series uses every call.
  explicit DebrisRecorder(const RigidWorld& world, double resample_hz = 30.0, double solver_rate_hz = 0.0);

  void record();
  void finish();
  // The series so far and the resampling's carry (solver/checkpoint.h).
  void checkpoint(StateArchive& ar);

  int body_count() const { return int(bodies_.size()); }
  const std::string& name(int body) const { return bodies_.at(body).name; }
  const DebrisSeries& solver_rate(int body) const { return bodies_.at(body).solver; }
  const DebrisSeries& resampled(int body) const { return bodies_.at(body).resampled; }
  double resample_hz() const { return resample_hz_; }

 private:
  struct Sample {
    double t = 0.0;
    Eigen::Vector3d x, v, w;
    RigidQuaternion q;
  };
  struct Track {
    std::string name;
    double mass = 0.0;
    DebrisSeries solver, resampled;
    Sample last_kept;          // last solver-rate sample stored
    Sample previous;           // last record() state, for interpolation
    bool has_pending = false;  // a resampled sample waiting for the end of its window
    Sample pending;
    double window_start_t = 0.0;
    Eigen::Vector3d window_start_v;
  };
  void append(DebrisSeries& s, const Sample& x, const Eigen::Vector3d& a, double mass) const;
  void cross(Track& track, long long j, const Sample& s);

  const RigidWorld& world_;
  double resample_hz_;
  double solver_interval_;
  bool started_ = false;
  long long next_j_ = 0;  // next half-period index j, at time j * T / 2
  std::vector<Track> bodies_;
};

}  // namespace flume
