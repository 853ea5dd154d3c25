// The progress lines of `flume run`: simulated time, wall time, speed and the time left, printed on a steady
// wall-clock cadence (the first line soon, then every `every_s`) whatever the time step does.
#pragma once
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace flume {

class Progress {
 public:
  using Clock = std::chrono::steady_clock;
  // `t_start`: the simulated time this segment starts at (after a resume, the checkpoint's).
  Progress(double end_time, double t_start, std::size_t particles, double first_s = 2.0, double every_s = 10.0,
           std::FILE* out = stderr);
  // Called after every step; prints a line when its time has come.
  void step(double t, long steps, double dt);
  // The line for the state given, with the wall time `wall_s` since the segment started (for tests).
  static std::string line(double t, double end_time, double t_start, long steps, long steps_start, double dt,
                          double wall_s, std::size_t particles);

 private:
  double end_time_, t_start_;
  std::size_t particles_;
  double every_s_;
  std::FILE* out_;
  Clock::time_point start_, next_;
  long steps_start_ = -1;
};

}  // namespace flume
