// Reading and checking an inflow's section record (solver/inflow.h).
#include "solver/inflow.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/errors.h"
#include "store/h5/run_file.h"

namespace flume {

namespace {
std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

void load_inflow_record(Scene& scene) {
  InflowSettings& F = scene.inflow;
  const std::string& file = F.record;
  auto bad = [&](const std::string& field, const std::string& what) {
    throw InputError(scene.file, field, "'" + file + "': " + what);
  };
  if (!std::ifstream(file).good())
    bad("inflow.record",
        "cannot open it (a result.h5 of a run with a section instrument; a relative path is read "
        "from the working directory)");
  const std::string g = "/sections/" + F.section;
  try {
    h5::Reader r(file);
    if (!r.exists("/sections"))
      bad("inflow.record",
          "has no /sections: it is not the result of a run with a section instrument (basin scenes "
          "record one, apron_inflow at x = 4.35 m)");
    if (!r.exists(g)) {
      std::string names;
      for (const auto& n : r.list("/sections")) names += (names.empty() ? "" : ", ") + n;
      bad("inflow.section", "has no section '" + F.section + "' (it has: " + names + ")");
    }
    for (const char* k : {"time", "depth", "velocity"})
      if (!r.exists(g + "/" + k)) bad("inflow.section", g + "/" + k + " is missing: the record is malformed");
    F.time = r.read_vector(g + "/time");
    F.depth = r.read_vector(g + "/depth");
    F.velocity = r.read_vector(g + "/velocity");
    F.y.clear();
    if (r.exists(g + "/y")) F.y = r.read_vector(g + "/y");
    F.record_dimension = F.y.empty() ? 2 : 3;
    F.record_bin_width_m = F.y.empty() ? 0.0 : r.number_attribute(g, "bin_width_m");
    F.record_floor_m = r.number_attribute(g, "floor_m");
    F.z.clear();
    F.profile.clear();
    if (r.exists(g + "/velocity_profile")) {
      if (!r.exists(g + "/z")) bad("inflow.section", g + "/velocity_profile needs " + g + "/z");
      F.z = r.read_vector(g + "/z");
      F.profile = r.read_vector(g + "/velocity_profile");
    }
    const double x_rec = r.number_attribute(g, "x_m");
    if (std::fabs(x_rec - F.x_m) > 0.5 * scene.solver.dx)
      throw InputError(scene.file, "inflow.x_m",
                       "must be where the record's section lies, x = " + fmt(x_rec) + " m in '" + file +
                           "' (within half a cell; got " + fmt(F.x_m) + ")");
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    bad("inflow.record", std::string("is not a readable result file: ") + e.what());
  }
  const size_t nt = F.time.size(), nb = F.bins();
  if (nt < 2)
    bad("inflow.section", g + "/time must hold at least 2 samples (got " + std::to_string(nt) + ")");
  for (size_t i = 1; i < nt; ++i)
    if (!(F.time[i] > F.time[i - 1]))
      bad("inflow.section", g + "/time must increase (sample " + std::to_string(i) + ")");
  if (F.depth.size() != nt * nb || F.velocity.size() != nt * nb)
    bad("inflow.section", g + "/depth and velocity must hold time x bins = " + std::to_string(nt) + " x " +
                              std::to_string(nb) + " values");
  if (!F.z.empty()) {
    if (F.profile.size() != nt * nb * F.z.size())
      bad("inflow.section", g + "/velocity_profile must hold time x bins x layers = " + std::to_string(nt) +
                                " x " + std::to_string(nb) + " x " + std::to_string(F.z.size()) + " values");
    for (double u : F.profile)
      if (!std::isfinite(u)) bad("inflow.section", g + "/velocity_profile must be finite");
    if (!(F.z.front() > F.record_floor_m))
      bad("inflow.section", g + "/z must lie above the floor_m attribute");
  }
  for (size_t i = 0; i < nt * nb; ++i) {
    if (!(std::isfinite(F.depth[i]) && F.depth[i] >= 0))
      bad("inflow.section",
          g + "/depth must be finite and >= 0 (value " + std::to_string(i) + ": " + fmt(F.depth[i]) + ")");
    if (!std::isfinite(F.velocity[i]))
      bad("inflow.section", g + "/velocity must be finite (value " + std::to_string(i) + ")");
  }
  if (F.record_dimension == 3 && !(F.record_bin_width_m > 0))
    bad("inflow.section", g + " has y but no positive bin_width_m attribute");
  if (F.record_dimension == 3 && scene.dimension == 2)
    bad("inflow.section",
        "is a 3D record (bins across y); a 2D scene needs a 2D record (a 3D scene takes either)");
  if (scene.solver.end_time > F.time.back() + 1e-9)
    throw InputError(scene.file, "solver.end_time",
                     "must not exceed the inflow record's end, t = " + fmt(F.time.back()) + " s in '" + file +
                         "' (got " + fmt(scene.solver.end_time) + ")");
}

namespace {
// The record's bin across y that holds y, and the two samples around t with the weight of the later one.
struct Where {
  size_t j = 0, i0 = 0, i1 = 0;
  double w = 0;
};
Where locate(const InflowSettings& f, double t, double y) {
  Where p;
  const size_t nt = f.time.size(), nb = f.bins();
  if (nb > 1) {
    const double edge = f.y.front() - 0.5 * f.record_bin_width_m;
    const double b = std::floor((y - edge) / f.record_bin_width_m);
    p.j = static_cast<size_t>(std::clamp(b, 0.0, double(nb - 1)));
  }
  if (t <= f.time.front()) return p;
  if (t >= f.time.back()) {
    p.i0 = p.i1 = nt - 1;
    return p;
  }
  p.i1 = static_cast<size_t>(std::upper_bound(f.time.begin(), f.time.end(), t) - f.time.begin());
  p.i0 = p.i1 - 1;
  p.w = (t - f.time[p.i0]) / (f.time[p.i1] - f.time[p.i0]);
  return p;
}
}  // namespace

InflowSample inflow_at(const InflowSettings& f, double t, double y) {
  const Where p = locate(f, t, y);
  const size_t nb = f.bins();
  auto lerp = [&](const std::vector<double>& a) {
    return (1 - p.w) * a[p.i0 * nb + p.j] + p.w * a[p.i1 * nb + p.j];
  };
  return {lerp(f.depth), lerp(f.velocity)};
}

double inflow_velocity_at(const InflowSettings& f, double t, double y, double height_m) {
  if (f.z.empty()) return inflow_at(f, t, y).velocity;
  const Where p = locate(f, t, y);
  const size_t nb = f.bins(), nz = f.z.size();
  const double layer = 2 * (f.z.front() - f.record_floor_m);
  const size_t l = static_cast<size_t>(std::clamp(std::floor(height_m / layer), 0.0, double(nz - 1)));
  return (1 - p.w) * f.profile[(p.i0 * nb + p.j) * nz + l] + p.w * f.profile[(p.i1 * nb + p.j) * nz + l];
}

}  // namespace flume
