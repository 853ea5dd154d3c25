// `flume surrogate adapt`: a campaign grown batch by batch (surrogate/adaptive.h) until the kriging
// surrogate reaches a target Q2 or a target width of the exceedance probability's interval, or the run
// budget is spent. The campaign is an ordinary one of the store: its spec's design is the first batch, each
// later batch is appended as further design points (CampaignStore via the campaign engine), so a stopped
// job is resumed by running the same command again: the added points are read back from the store, pending
// runs are run, and the next batch is proposed from the same data as before.
#pragma once
#include <cstdint>
#include <string>

#include "surrogate/adaptive.h"

namespace flume::surrogate {

struct AdaptiveCampaignOptions {
  std::string spec_file, db_file, metric;
  AdaptiveSettings adapt;
  std::size_t max_runs = 100;
  double target_q2 = 0;     // 0: none
  double target_width = 0;  // of the exceedance interval at adapt.threshold, once runs lie on both sides; 0: none
  std::size_t folds = 5;
  int workers = 1;
};

struct AdaptiveCampaignOutcome {
  std::size_t runs = 0, batches = 0;
  double q2 = 0, p = 0, width = 0;
  bool reached = false;
  int exit_code = 0;
};

AdaptiveCampaignOutcome run_adaptive_campaign(const AdaptiveCampaignOptions& options);

}  // namespace flume::surrogate
