#include "solver/rigid/debris_recorder.h"

#include "solver/checkpoint.h"

#include <cmath>
#include <stdexcept>

namespace flume {
namespace {

std::array<double, 3> arr(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// State at time t between two records a and b: cubic Hermite position from the end positions and velocities
// (exact when the acceleration is constant over the interval), linear velocities, slerp orientation.
template <class S>
S interpolate(const S& a, const S& b, double t) {
  const double h = b.t - a.t;
  S s;
  s.t = t;
  if (!(h > 0.0)) {
    s = b;
    s.t = t;
    return s;
  }
  const double u = (t - a.t) / h;
  const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
  const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
  s.x = h00 * a.x + h10 * h * a.v + h01 * b.x + h11 * h * b.v;
  s.v = (1 - u) * a.v + u * b.v;
  s.w = (1 - u) * a.w + u * b.w;
  s.q = a.q.slerp(u, b.q);  // Eigen's slerp takes the shorter arc
  return s;
}

}  // namespace

DebrisRecorder::DebrisRecorder(const RigidWorld& world, double resample_hz, double solver_rate_hz)
    : world_(world), resample_hz_(resample_hz), solver_interval_(solver_rate_hz > 0 ? 1.0 / solver_rate_hz : 0) {
  if (!(resample_hz > 0.0) || !std::isfinite(resample_hz))
    throw std::invalid_argument("DebrisRecorder: resample_hz must be > 0");
  if (!(solver_rate_hz >= 0.0)) throw std::invalid_argument("DebrisRecorder: solver_rate_hz must be >= 0");
}

void DebrisRecorder::append(DebrisSeries& s, const Sample& x, const Eigen::Vector3d& a, double mass) const {
  s.time.push_back(x.t);
  s.position.push_back(arr(x.x));
  s.orientation.push_back({x.q.w(), x.q.x(), x.q.y(), x.q.z()});
  s.velocity.push_back(arr(x.v));
  s.angular_velocity.push_back(arr(x.w));
  s.acceleration.push_back(arr(a));
  s.force.push_back(arr(mass * a));
  s.specific_force_body.push_back(arr(x.q.conjugate() * (a - world_.gravity())));
}

// The record stream has reached half-period j (time j T / 2) with state s. Even j: a sample time, held until
// its window closes. Odd j: a window edge, closing the held sample.
void DebrisRecorder::cross(Track& track, long long j, const Sample& s) {
  if (j % 2 != 0) {
    if (track.has_pending) {
      const double span = s.t - track.window_start_t;
      const Eigen::Vector3d a = span > 0 ? Eigen::Vector3d((s.v - track.window_start_v) / span)
                                         : Eigen::Vector3d::Zero();
      append(track.resampled, track.pending, a, track.mass);
      track.has_pending = false;
    }
    track.window_start_t = s.t;
    track.window_start_v = s.v;
  } else {
    track.pending = s;
    track.has_pending = true;
  }
}

void DebrisRecorder::record() {
  const double t = world_.time();
  const double half = 0.5 / resample_hz_;
  if (!started_) {
    started_ = true;
    bodies_.resize(world_.body_count());
    next_j_ = (long long)std::ceil(t / half - 1e-9);
  }
  if (int(bodies_.size()) != world_.body_count())
    throw std::logic_error("DebrisRecorder: bodies were added after recording started");

  // Half-period times passed since the previous record (the first record only matches one at its own time).
  long long j_end = next_j_;
  while ((j_end) * half <= t * (1 + 1e-12) + 1e-15) ++j_end;

  for (int i = 0; i < int(bodies_.size()); ++i) {
    Track& tr = bodies_[i];
    const BodyState st = world_.state(i);
    Sample now;
    now.t = t;
    now.x = st.position;
    now.v = st.velocity;
    now.w = st.angular_velocity;
    now.q = st.orientation;
    const bool first = tr.solver.size() == 0;
    if (first) {
      tr.name = world_.spec(i).name.empty() ? "D" + std::to_string(i + 1) : world_.spec(i).name;
      tr.mass = world_.mass(i);
      append(tr.solver, now, st.acceleration, tr.mass);
      tr.last_kept = now;
      tr.window_start_t = t;
      tr.window_start_v = now.v;
      for (long long j = next_j_; j < j_end; ++j) cross(tr, j, now);
    } else {
      if (!(t > tr.previous.t)) throw std::logic_error("DebrisRecorder: record() time did not advance");
      if (t - tr.last_kept.t >= solver_interval_ * (1 - 1e-9)) {
        append(tr.solver, now, (now.v - tr.last_kept.v) / (t - tr.last_kept.t), tr.mass);
        tr.last_kept = now;
      }
      for (long long j = next_j_; j < j_end; ++j) cross(tr, j, interpolate(tr.previous, now, j * half));
    }
    tr.previous = now;
  }
  next_j_ = j_end;
}

void checkpoint_state(StateArchive& ar, DebrisSeries& s) {
  ar(s.time);
  ar(s.position);
  ar(s.orientation);
  ar(s.velocity);
  ar(s.angular_velocity);
  ar(s.acceleration);
  ar(s.force);
  ar(s.specific_force_body);
}

void DebrisRecorder::checkpoint(StateArchive& ar) {
  ar.section("debris recorder");
  ar.expect("debris bodies", bodies_.size());
  ar(started_);
  ar(next_j_);
  for (Track& t : bodies_) {
    ar(t.solver);
    ar(t.resampled);
    for (Sample* x : {&t.last_kept, &t.previous, &t.pending}) {
      ar(x->t);
      ar(x->x);
      ar(x->v);
      ar(x->w);
      ar(x->q);
    }
    ar(t.has_pending);
    ar(t.window_start_t);
    ar(t.window_start_v);
  }
}

void DebrisRecorder::finish() {
  for (Track& tr : bodies_) {
    if (!tr.has_pending) continue;
    const double span = tr.previous.t - tr.window_start_t;
    const Eigen::Vector3d a =
        span > 0 ? Eigen::Vector3d((tr.previous.v - tr.window_start_v) / span) : Eigen::Vector3d::Zero();
    append(tr.resampled, tr.pending, a, tr.mass);
    tr.has_pending = false;
  }
}

}  // namespace flume
