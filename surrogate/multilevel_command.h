// `flume surrogate multilevel`: the multi-fidelity estimates of one metric over campaigns of a store, printed.
#pragma once
#include <string>
#include <vector>

namespace flume::surrogate {

// Levels high to low fidelity; costs per run (empty or 0: the campaigns' mean wall times).
void print_multilevel(const std::string& db_file, const std::vector<std::string>& levels,
                      const std::vector<double>& costs, const std::string& metric, double confidence);

}  // namespace flume::surrogate
