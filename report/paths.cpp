// `flume debris-paths RUN_DIR ... --out FILE.svg`: the top-down paths of the debris of one or more runs, as the
// comparative study's Figs. 11-13 draw them, with the guidelines the study compares against (Naito et al. 2014's
// 22.5 deg cone, Nistor et al. 2017's eq. 59 cone and eq. 58 longitudinal displacement), and a table of each
// debris' metrics on stdout.
#include "report/paths.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/command.h"
#include "common/errors.h"
#include "common/input/json_input.h"
#include "common/input/overrides.h"
#include "common/plot/figure.h"
#include "report/debris.h"
#include "report/geometry.h"
#include "report/map.h"
#include "store/h5/run_file.h"

namespace flume::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;


struct DebrisPath {
  std::string name;
  std::vector<double> x, y;  // resampled (30 Hz) centre positions
  double x0 = 0, y0 = 0, x_runup = 0, y_runup = 0, x_rest = 0, y_rest = 0;
  double longitudinal_max = 0, longitudinal_rest = 0, lateral_runup = 0, lateral_rest = 0;
  double spreading_runup = 0, spreading_rest = 0;
  double final_speed = std::nan("");  // m/s at the end of the run
  int at_rest = -1;                   // D<k>.at_rest: 1, 0, or -1 for a run written before it existed
  bool dammed = false;
};

struct RunPaths {
  std::string dir, scene_name, layout;
  ApronGeometry geometry;
  std::vector<DebrisPath> debris;
  double apex_x = 0, apex_y = 0;
  double rest_speed_m_s = 0.01, rest_hold_s = 1.0;  // debris.rest_speed_m_s, debris.rest_hold_s of the scene
};

// A dotted path in the run's scene JSON, or the default.
template <typename V>
V scene_value(const json& scene, const std::string& path, V fallback) {
  const json* node = &scene;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!node->is_object() || !node->contains(key)) return fallback;
    node = &(*node)[key];
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  try {
    return node->get<V>();
  } catch (const json::exception&) {
    return fallback;
  }
}

double metric(const json& metrics, const std::string& file, const std::string& name) {
  if (!metrics.contains(name) || !metrics[name].is_number())
    throw InputError(file, "metrics." + name, "missing: the run has no debris metrics of that name");
  return metrics[name].get<double>();
}

// `sets`: for runs written before run.json recorded the scene, the --set overrides they ran with, applied to
// the scene file that run.json names.
RunPaths read_run(const std::string& dir, const std::vector<Override>& sets) {
  RunPaths r;
  r.dir = dir;
  const std::string run_json = (fs::path(dir) / "run.json").string();
  const std::string h5_file = (fs::path(dir) / "result.h5").string();
  if (!std::ifstream(run_json))
    throw InputError(run_json, "", "cannot open (is " + dir + " the --out folder of a finished `flume run`?)");
  const json run = input::load_json_document(run_json, "run record");
  if (!fs::exists(h5_file)) throw InputError(h5_file, "", "missing: the run did not finish");
  json scene = run.value("scene_json", json::object());
  if (scene.empty()) {
    const std::string file = run.value("scene", "");
    if (file.empty() || !fs::exists(file))
      throw InputError(run_json, "scene_json",
                       "missing, and the scene file it names ('" + file +
                           "') is not there: run it again with this flume, which records the scene");
    scene = input::load_with_overrides(file, "scene file", sets);
  } else if (!sets.empty()) {
    throw cli::UsageError("--set", "only for runs whose run.json has no scene_json; " + run_json + " has one");
  }
  r.scene_name = scene.value("name", fs::path(dir).filename().string());
  r.layout = scene_value<std::string>(scene, "obstacles.layout", "0x0");
  ApronGeometry& g = r.geometry;
  g.quay_x_m = scene_value<double>(scene, "basin.quay_x_m", g.quay_x_m);
  g.end_x_m = scene_value<double>(scene, "basin.length_m", g.end_x_m);
  g.y_hi_m = scene_value<double>(scene, "basin.width_m", g.y_hi_m);
  g.layout = r.layout;
  g.layout_source = "scene";
  r.rest_speed_m_s = scene_value<double>(scene, "debris.rest_speed_m_s", r.rest_speed_m_s);
  r.rest_hold_s = scene_value<double>(scene, "debris.rest_hold_s", r.rest_hold_s);
  g.obstacles = obstacle_layout(r.layout, 0.5 * (g.y_lo_m + g.y_hi_m));

  const json metrics = run.value("metrics", json::object());
  h5::Reader h5(h5_file);
  if (!h5.exists("/debris")) throw InputError(h5_file, "/debris", "missing: the run has no debris");
  for (const std::string& name : h5.list("/debris")) {
    DebrisPath p;
    p.name = name;
    const std::string ds = "/debris/" + name + "/resampled/position";
    if (!h5.exists(ds)) throw InputError(h5_file, ds, "missing");
    const std::vector<double> xyz = h5.read_vector(ds);
    for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
      p.x.push_back(xyz[i]);
      p.y.push_back(xyz[i + 1]);
    }
    auto m = [&](const char* what) { return metric(metrics, run_json, name + "." + what); };
    p.x0 = m("initial_x_m");
    p.y0 = m("initial_y_m");
    p.x_runup = m("runup_x_m");
    p.y_runup = m("runup_y_m");
    p.x_rest = m("rest_x_m");
    p.y_rest = m("rest_y_m");
    p.longitudinal_max = m("longitudinal_max_m");
    p.longitudinal_rest = m("longitudinal_rest_m");
    p.lateral_runup = m("lateral_runup_m");
    p.lateral_rest = m("lateral_rest_m");
    p.spreading_runup = m("spreading_runup_deg");
    p.spreading_rest = m("spreading_rest_deg");
    p.dammed = metrics.contains(name + ".dammed") && metrics[name + ".dammed"].get<double>() > 0.5;
    if (metrics.contains(name + ".final_speed_m_s")) p.final_speed = m("final_speed_m_s");
    if (metrics.contains(name + ".at_rest")) p.at_rest = m("at_rest") > 0.5 ? 1 : 0;
    r.apex_x += p.x0;
    r.apex_y += p.y0;
    r.debris.push_back(std::move(p));
  }
  if (r.debris.empty()) throw InputError(h5_file, "/debris", "holds no debris");
  r.apex_x /= static_cast<double>(r.debris.size());
  r.apex_y /= static_cast<double>(r.debris.size());
  return r;
}

void draw_run(plot::Axes& ax, const RunPaths& r) {
  const int n = static_cast<int>(r.debris.size());
  char title[200];
  std::snprintf(title, sizeof title, "%s: obstacles %s, %d debris", r.scene_name.c_str(), r.layout.c_str(), n);
  ax.title(title);
  draw_apron(ax, r.geometry);
  const plot::Color vermillion = plot::palette(3), purple = plot::palette(4), grey{90, 90, 90};
  draw_cone(ax, r.apex_x, r.apex_y, r.geometry.end_x_m, kNaitoSpreadingDeg, vermillion, plot::Dash::kDashed,
            "Naito 22.5 deg");
  char lab[80];
  std::snprintf(lab, sizeof lab, "Nistor eq. 59: %.2f deg", nistor_spreading_deg(n));
  draw_cone(ax, r.apex_x, r.apex_y, r.geometry.end_x_m, nistor_spreading_deg(n), purple, plot::Dash::kDotted, lab);
  const double x58 = r.apex_x + nistor_longitudinal_m(n);
  std::snprintf(lab, sizeof lab, "Nistor eq. 58: %.2f m", nistor_longitudinal_m(n));
  if (x58 < r.geometry.end_x_m) ax.vline(x58, {.color = grey, .width = 1.2, .dash = plot::Dash::kDashDot, .label = lab});
  std::vector<double> x0, y0;
  // The end of the run is a rest position only where the debris has come to rest (D<k>.at_rest; a run without
  // the flag counts as at rest, as it was drawn before): the others are marked apart, as still moving.
  bool rest_labelled = false, moving_labelled = false;
  for (std::size_t k = 0; k < r.debris.size(); ++k) {
    const DebrisPath& p = r.debris[k];
    // Okabe & Ito's blue, orange, green, sky blue, then brown and grey: not the cones' colours.
    static const plot::Color colors[] = {plot::palette(0), plot::palette(1), plot::palette(2), plot::palette(5),
                                         plot::Color{140, 80, 20}, plot::Color{110, 110, 110}};
    const plot::Color c = colors[k % 6];
    ax.line(p.x, p.y, {.color = c, .width = 1.2});
    ax.text(p.x_runup + 0.05, p.y_runup, p.name, {.size = 10.0, .color = c});  // named at its run-up, not in the legend
    ax.scatter({p.x_runup}, {p.y_runup},
               {.color = c, .marker = plot::Marker::kCircle, .size = 7, .label = k == 0 ? "run-up (circles)" : ""});
    const bool moving = p.at_rest == 0;
    bool& labelled = moving ? moving_labelled : rest_labelled;
    ax.scatter({p.x_rest}, {p.y_rest},
               {.color = c,
                .marker = moving ? plot::Marker::kCross : plot::Marker::kDiamond,
                .size = 7,
                .label = labelled ? "" : moving ? "end of run, still moving (crosses)" : "rest (diamonds)"});
    labelled = true;
    x0.push_back(p.x0);
    y0.push_back(p.y0);
  }
  ax.scatter(x0, y0, {.color = plot::Color{0, 0, 0}, .marker = plot::Marker::kSquare, .size = 5, .label = "initial"});
  // Upper left: above the field's start, outside the cones, where no debris goes.
  ax.legend(plot::Legend::kUpperLeft);
}

void print_run(const RunPaths& r) {
  const int n = static_cast<int>(r.debris.size());
  std::printf("%s (%s, obstacles %s, %d debris; apex %.3f, %.3f m)\n", r.dir.c_str(), r.scene_name.c_str(),
              r.layout.c_str(), n, r.apex_x, r.apex_y);
  std::printf(
      "  debris  long_max_m  long_rest_m  lat_runup_m  lat_rest_m  angle_runup_deg  angle_rest_deg  dammed  "
      "speed_end_m_s  at_rest\n");
  double sum = 0;
  int naito = 0, nistor = 0, moving = 0;
  for (const auto& p : r.debris) {
    std::printf("  %-6s  %10.3f  %11.3f  %11.3f  %10.3f  %15.2f  %14.2f  %6s  %13.3f  %7s\n", p.name.c_str(),
                p.longitudinal_max, p.longitudinal_rest, p.lateral_runup, p.lateral_rest, p.spreading_runup,
                p.spreading_rest, p.dammed ? "yes" : "no", p.final_speed,
                p.at_rest < 0 ? "?" : p.at_rest ? "yes" : "no");
    moving += p.at_rest == 0;
    sum += p.longitudinal_max;
    for (double a : {p.spreading_runup, p.spreading_rest}) {
      naito += std::fabs(a) > kNaitoSpreadingDeg;
      nistor += std::fabs(a) > nistor_spreading_deg(n);
    }
  }
  const double mean = sum / n, eq58 = nistor_longitudinal_m(n);
  std::printf("  mean longitudinal_max %.3f m; Nistor eq. 58 (3.58 - 0.09 N) %.3f m: %+.1f %%\n", mean, eq58,
              100.0 * (mean - eq58) / eq58);
  std::printf("  angles (run-up and rest, %d) beyond Naito 22.5 deg: %d; beyond Nistor eq. 59 %.2f deg: %d\n", 2 * n,
              naito, nistor_spreading_deg(n), nistor);
  if (moving > 0)
    std::printf("  %d of %d not at rest at the end (slower than %g m/s over the run's last %g s): their 'rest' columns "
                "are end-of-run positions\n",
                moving, n, r.rest_speed_m_s, r.rest_hold_s);
}

}  // namespace

void add_debris_paths_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> dirs, sets;
    std::string out;
  };
  auto a = std::make_shared<Args>();
  CLI::Option* dirs = app.add_option("RUN_DIR", a->dirs, "a finished run's folder")->required();
  CLI::Option* sets = cli::add_set_option(
      app, a->sets,
      "after a RUN_DIR, for that run: for runs older than run.json's scene_json, the overrides the run was started "
      "with");
  app.add_option("--out", a->out, "the .svg file to write")->required();
  const CLI::App* self = &app;
  cli::on_parse(app, [a, self, dirs, sets]() -> int {
    // Each --set belongs to the RUN_DIR before it: the order of the line decides.
    std::vector<std::vector<Override>> run_sets;
    std::size_t next_set = 0;
    for (const CLI::Option* o : self->parse_order()) {
      if (o == dirs) {
        run_sets.emplace_back();
      } else if (o == sets) {
        if (run_sets.empty()) throw cli::UsageError("--set", "belongs after the RUN_DIR it applies to");
        run_sets.back().push_back(parse_override(a->sets.at(next_set++)));
      }
    }
    const std::vector<std::string>& dirs_in_order = a->dirs;
    const std::string& out = a->out;
    std::vector<RunPaths> runs;
    for (std::size_t k = 0; k < dirs_in_order.size(); ++k) runs.push_back(read_run(dirs_in_order[k], run_sets.at(k)));
    plot::Figure fig(static_cast<int>(runs.size()), 1, 1000, 520 * static_cast<int>(runs.size()));
    for (std::size_t k = 0; k < runs.size(); ++k) {
      draw_run(fig.axes(static_cast<int>(k), 0), runs[k]);
      print_run(runs[k]);
    }
    fig.save(out);
    std::printf("wrote %s\n", out.c_str());
    return kExitOk;
  });
}

}  // namespace flume::report
