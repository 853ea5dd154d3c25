#include "surrogate/posterior_refine.h"

#include <cstdio>
#include <string>

#include "calibration/calibrate.h"
#include "calibration/stored_spec.h"
#include "surrogate/series_data.h"
#include "surrogate/series_posterior.h"

namespace flume::surrogate {

int refine_posterior(const std::string& db_file, const std::string& calibration,
                     const PosteriorSettings& posterior, const RefineSettings& refine) {
  for (int round = 1; round <= refine.rounds; ++round) {
    PosteriorSettings s = posterior;
    s.draws = refine.points;
    s.seed = posterior.seed + static_cast<std::uint64_t>(round);
    Posterior post;
    std::string spec_json;
    if (refine.series) {
      const SeriesData d = load_calibration_series(db_file, calibration, round);
      post = series_posterior(d, s);
      spec_json = d.spec_json;
    } else {
      const MisfitData d = load_calibration_misfit(db_file, calibration, round);
      post = misfit_posterior(d, s);
      spec_json = d.spec_json;
    }
    std::string intervals;
    for (const auto& p : post.parameters) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s %s [%.6g, %.6g]", intervals.empty() ? "" : ";", p.name.c_str(), p.lo,
                    p.hi);
      intervals += buf;
    }
    std::printf("# refine round %d: posterior from %zu evaluations (Q2 %.3f):%s; running %zu draws\n", round,
                post.evaluations, post.q2, intervals.c_str(), post.draws.size());
    std::fflush(stdout);
    const calibration::CalibrationSpec spec = calibration::parse_stored_calibration_spec(
        spec_json, db_file + " (calibration '" + calibration + "')");
    const int rc =
        calibration::evaluate_points(spec, db_file, kRefinePhase, round, post.draws, refine.workers);
    if (rc != 0) return rc;
  }
  return 0;
}

}  // namespace flume::surrogate
