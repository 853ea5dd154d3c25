#include "calibration/commands.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/records.h"
#include "calibration/spec.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"
#include "store/h5/run_file.h"

namespace flume::calibration {
namespace {

const char* kUsage =
    "usage:\n"
    "  flume calibrate SPEC.json --db FILE --out DIR [--workers N]\n"
    "  flume calibrate target RESULT.h5 --out CSV [--gauge NAME ...] [--noise-m SIGMA] [--seed N] [--from "
    "T0] "
    "[--to T1]\n"
    "  flume calibrate history --db FILE [--name NAME]\n";

double parse_number(const std::string& flag, const std::string& text, double lo, double hi) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end || errno || !(v >= lo && v <= hi))
    throw InputError(
        "", flag,
        "must be a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got '" + text + "')");
  return v;
}

int target_main(const std::vector<std::string>& args) {
  std::string h5, out;
  std::vector<std::string> gauges;
  double noise = 0, from = 0, to = 1e30;
  std::uint64_t seed = 1;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw InputError("", a, "needs a value");
      return args[++i];
    };
    if (a == "--out")
      out = value();
    else if (a == "--gauge")
      gauges.push_back(value());
    else if (a == "--noise-m")
      noise = parse_number(a, value(), 0, 1);
    else if (a == "--seed")
      seed = static_cast<std::uint64_t>(parse_number(a, value(), 0, 4294967295.0));
    else if (a == "--from")
      from = parse_number(a, value(), 0, 1e6);
    else if (a == "--to")
      to = parse_number(a, value(), 0, 1e6);
    else if (h5.empty() && a.rfind("--", 0) != 0)
      h5 = a;
    else
      throw InputError("", a, std::string("unknown argument\n") + kUsage);
  }
  if (h5.empty() || out.empty())
    throw InputError("", "", std::string("target needs RESULT.h5 and --out CSV\n") + kUsage);
  std::vector<SimRecord> records;
  try {
    if (gauges.empty()) gauges = h5::Reader(h5).list("/gauges");
    for (const auto& g : gauges) records.push_back(read_sim_gauge(h5, g));
  } catch (const std::exception& e) {
    throw InputError(h5, "gauges", e.what());
  }
  if (gauges.empty()) throw InputError(h5, "/gauges", "has no gauge records");
  const double rms = write_target_csv(out, gauges, records, noise, seed, from, to);
  std::printf("wrote %s: %zu gauge(s), noise sigma %g m (seed %llu), noise RMS %.6g m\n", out.c_str(),
              gauges.size(), noise, static_cast<unsigned long long>(seed), rms);
  return kExitOk;
}

int history_main(const std::vector<std::string>& args) {
  std::string db_file, name;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--db" && i + 1 < args.size())
      db_file = args[++i];
    else if (args[i] == "--name" && i + 1 < args.size())
      name = args[++i];
    else
      throw InputError("", args[i], std::string("unknown argument\n") + kUsage);
  }
  if (db_file.empty()) throw InputError("", "--db", "is required");
  store::CampaignStore db(db_file, true);
  std::printf("calibration,phase,start,seq,run,objective,params\n");
  for (const auto& c : db.campaigns()) {
    if (!name.empty() && c.name != name) continue;
    for (const auto& e : db.evaluations(c.id)) {
      std::string params = e.params_json;
      for (auto& ch : params)
        if (ch == '"') ch = '\'';
      std::printf("%s,%s,%lld,%lld,%lld,%.10g,\"%s\"\n", c.name.c_str(), e.phase.c_str(),
                  static_cast<long long>(e.start), static_cast<long long>(e.seq),
                  static_cast<long long>(e.run), e.value, params.c_str());
    }
  }
  return kExitOk;
}

int calibrate(const std::vector<std::string>& args) {
  std::string spec_file;
  CalibrateOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw InputError("", a, "needs a value");
      return args[++i];
    };
    if (a == "--db")
      options.db_file = value();
    else if (a == "--out")
      options.out_dir = value();
    else if (a == "--workers")
      options.workers = static_cast<int>(parse_number(a, value(), 1, 1024));
    else if (spec_file.empty() && a.rfind("--", 0) != 0)
      spec_file = a;
    else
      throw InputError("", a, std::string("unknown argument\n") + kUsage);
  }
  if (spec_file.empty()) throw InputError("", "", std::string("SPEC.json is required\n") + kUsage);
  if (options.db_file.empty())
    throw InputError("", "--db", "is required (the campaign store to keep the runs in)");
  if (options.out_dir.empty())
    throw InputError("", "--out", "is required (where calibration.json and the plots go)");
  const CalibrationSpec spec = load_calibration_spec(spec_file);
  CalibrationResult result;
  const int code = run_calibration(spec, options, result);
  if (!result.best.empty()) {
    std::printf(
        "%s: objective %.6g m (RMS %.6g m), %d optimizer + %d profile evaluations, %lld run(s) in the store "
        "(%lld run now), status %s\n",
        spec.name.c_str(), result.best_terms.value, result.best_terms.rms_m, result.optimizer_evaluations,
        result.profile_evaluations, static_cast<long long>(result.runs_total),
        static_cast<long long>(result.runs_executed), result.status.c_str());
    for (size_t j = 0; j < spec.parameters.size(); ++j)
      std::printf("  %s = %.6g\n", spec.parameters[j].path.c_str(), result.best[j]);
    std::printf("wrote %s/calibration.json\n", options.out_dir.c_str());
  }
  return code;
}

}  // namespace

int calibrate_main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
      std::fputs(kUsage, args.empty() ? stderr : stdout);
      return args.empty() ? kExitInvalidInput : kExitOk;
    }
    if (args[0] == "target") return target_main({args.begin() + 1, args.end()});
    if (args[0] == "history") return history_main({args.begin() + 1, args.end()});
    return calibrate(args);
  } catch (const InputError& e) {
    std::fprintf(stderr, "flume calibrate: %s\n", e.what());
    return kExitInvalidInput;
  } catch (const store::StoreError& e) {
    std::fprintf(stderr, "flume calibrate: store: %s\n", e.what());
    return kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flume calibrate: %s\n", e.what());
    return kExitInternal;
  }
}

}  // namespace flume::calibration
