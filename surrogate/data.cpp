// Training data from the store, through the report's read-only campaign reader.
#include "surrogate/data.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "campaigns/spec.h"
#include "common/errors.h"
#include "report/campaign_data.h"

namespace flume::surrogate {

double design_value(const sampling::Distribution& d, bool is_text, double number, const std::string& text) {
  if (d.type != sampling::DistributionType::kChoice) return number;
  if (is_text) {
    const auto it = std::find(d.text_choices.begin(), d.text_choices.end(), text);
    return it == d.text_choices.end() ? std::nan("") : static_cast<double>(it - d.text_choices.begin());
  }
  for (std::size_t i = 0; i < d.numeric_choices.size(); ++i)
    if (d.numeric_choices[i] == number) return static_cast<double>(i);
  return std::nan("");
}

TrainingData load_training_data(const std::string& db_file, const std::string& campaign, const std::string& metric,
                                std::size_t min_runs, const std::string& given) {
  const report::CampaignData c = report::load_campaign(db_file, campaign);
  TrainingData t;
  t.db_file = db_file;
  t.campaign = c.record.name;
  t.campaign_id = c.record.id;
  t.metric = metric;
  const campaigns::CampaignSpec spec =
      campaigns::parse_spec_parameters(c.record.spec, db_file + ": campaigns." + c.record.name + ".spec");
  if (spec.parameters.empty())
    throw InputError(db_file, "--campaign",
                     "campaign '" + t.campaign + "' has no parameter distributions (a list design): a surrogate "
                     "needs a sampled design");
  for (const auto& p : spec.parameters) {
    t.inputs.push_back(p.path);
    t.distributions.push_back(p.distribution);
  }
  t.correlations = spec.correlations;
  t.given = given;
  for (const std::string* name : {&metric, &given}) {
    if (name->empty() || std::find(c.metric_names.begin(), c.metric_names.end(), *name) != c.metric_names.end())
      continue;
    std::string names;
    for (const auto& n : c.metric_names) names += (names.empty() ? "" : ", ") + n;
    throw InputError(db_file, name == &metric ? "--metric" : "--given",
                     "campaign '" + t.campaign + "' has no metric '" + *name + "' (it has: " +
                         (names.empty() ? "none yet" : names) + ")");
  }
  std::set<std::int64_t> seen;
  for (const auto& row : c.rows) {
    if (!row.ok() || !seen.insert(row.run_id).second) continue;
    std::vector<double> x;
    for (std::size_t j = 0; j < t.inputs.size(); ++j) {
      const int k = c.parameter_index(t.inputs[j]);
      const auto& v = row.params.at(static_cast<std::size_t>(k));
      x.push_back(design_value(t.distributions[j], v.is_text, v.number, v.text));
    }
    if (std::any_of(x.begin(), x.end(), [](double v) { return !std::isfinite(v); })) continue;
    const auto m = row.metrics.find(metric);
    const bool inside = given.empty() ? m != row.metrics.end() : row.metrics.count(given) > 0;
    if (m == row.metrics.end() || !inside) {
      t.runs_without_metric += m == row.metrics.end();
      if (!inside) t.x_outside.push_back(std::move(x));
      continue;
    }
    t.run_ids.push_back(row.run_id);
    t.x.push_back(std::move(x));
    t.y.push_back(m->second);
  }
  if (t.y.size() < min_runs)
    throw InputError(db_file, "--campaign",
                     "campaign '" + t.campaign + "' has " + std::to_string(t.y.size()) + " finished run(s) with '" +
                         metric + "'; a surrogate needs at least " + std::to_string(min_runs));
  return t;
}

}  // namespace flume::surrogate
