// Analytic models that stand in for the solver: `flume model NAME --out DIR --set name=value ...` writes the
// same run.json as `flume run`, so campaigns, their store and the report can be tested in seconds.
//   ishigami: y = sin x1 + a sin^2 x2 + b x3^4 sin x1, a = 7, b = 0.1, inputs on [-pi, pi]
//             (Ishigami & Homma 1990; its Sobol' indices are known in closed form).
//   test:     y = x + 10 y_in + 100 z; `behaviour` ok|segfault|hang|unstable|fail picks how the run ends,
//             after `sleep_s` seconds; for the crash, hang and kill tests.
//   gauge:    TEST STAND-IN for the Waseda scene (calibration tests): WG1..WG4 elevation records written to
//             result.h5 (/gauges/<name>/{time, elevation}, 100 Hz) and their peak/arrival metrics, from a
//             reservoir draining through the gate (orifice law) under the scene's hold f(t) and a linear long
//             wave to the gauges. Its inputs are the scene's paths (reservoir.forcing.model|t99_s|table[.i.j],
//             reservoir.gate_height_m, reservoir.fill_level_m, basin.still_water_m, solver.end_time), so a
//             calibration spec moves from the stand-in to the scene unchanged. Not a model of the flume.
//   debris:   SYNTHETIC stand-in for the coupled debris solver (not physics): D<k>.* debris metrics, a load
//             cell and a gauge from friction, restitution, n_debris (3|6), wave_scale and obstacles.layout
//             (0x0|5x1|5x2), shaped by Nistor et al. (2017) eqs. 58-59; lets the report be exercised.
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace flume::campaigns {

// The model's input names, or empty when there is no such model.
std::vector<std::string> model_inputs(const std::string& model);
std::vector<std::string> model_names();

// Empty when the inputs (name -> JSON text) are acceptable, else "<name>: <problem>".
std::string check_model_inputs(const std::string& model,
                               const std::vector<std::pair<std::string, std::string>>& inputs);

// `flume model NAME --out DIR [--set name=value ...]`: runs the model on inputs check_model_inputs() accepted,
// writes DIR/run.json and returns the exit code `flume run` would.
int run_model(const std::string& model, const std::string& out_dir,
              const std::vector<std::pair<std::string, std::string>>& sets);

}  // namespace flume::campaigns
