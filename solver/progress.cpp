#include "solver/progress.h"

#include <string>

#include "common/duration.h"

namespace flume {

Progress::Progress(double end_time, double t_start, std::size_t particles, double first_s, double every_s,
                   std::FILE* out)
    : end_time_(end_time),
      t_start_(t_start),
      particles_(particles),
      every_s_(every_s),
      out_(out),
      start_(Clock::now()),
      next_(start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(first_s))) {}

void Progress::step(double t, long steps, double dt) {
  if (steps_start_ < 0) steps_start_ = steps - 1;
  const Clock::time_point now = Clock::now();
  if (now < next_) return;
  const double wall = std::chrono::duration<double>(now - start_).count();
  std::fprintf(out_, "%s\n", line(t, end_time_, t_start_, steps, steps_start_, dt, wall, particles_).c_str());
  std::fflush(out_);
  const auto every = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(every_s_));
  while (next_ <= now) next_ += every;
}

std::string Progress::line(double t, double end_time, double t_start, long steps, long steps_start, double dt,
                           double wall_s, std::size_t particles) {
  // Speeds over the whole segment: the time step varies from step to step, the average does not jump.
  const double sim_per_wall = wall_s > 0 ? (t - t_start) / wall_s : 0;
  const double particle_steps = double(steps - steps_start) * double(particles);
  const double eta = sim_per_wall > 0 ? (end_time - t) / sim_per_wall : -1;
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "t = %.3f s / %.3f s (%.0f %%), step %ld, dt = %.3g s | wall %s, %.3g sim-s/wall-s, "
                "%.3g particle-steps/s, ETA %s",
                t, end_time, end_time > 0 ? 100.0 * t / end_time : 0.0, steps, dt, hms(wall_s).c_str(),
                sim_per_wall, wall_s > 0 ? particle_steps / wall_s : 0.0, t >= end_time ? "0:00" : hms(eta).c_str());
  return buf;
}

}  // namespace flume
