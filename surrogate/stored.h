// Surrogates kept in the campaign store: fitted once per (campaign, metric, kind) and refitted only when the
// runs, their values or the settings changed, so `flume surrogate fit` can be repeated after a campaign grows.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "store/db/campaign_store.h"
#include "surrogate/fit.h"

namespace flume::surrogate {

struct StoredFit {
  store::SurrogateRecord record;
  bool refitted = false;  // false: the stored fit was current
};

StoredFit fit_and_store(const std::string& db_file, const std::string& campaign, const std::string& metric,
                        const FitSettings& settings, bool force = false);

// The stored surrogate; throws flume::InputError (naming the file, the campaign and the metric) when none.
store::SurrogateRecord stored_surrogate(const std::string& db_file, const std::string& campaign,
                                        const std::string& metric, Kind kind);

// Every surrogate stored for the campaign (without the models).
std::vector<store::SurrogateRecord> stored_surrogate_list(const std::string& db_file, const std::string& campaign);

}  // namespace flume::surrogate
