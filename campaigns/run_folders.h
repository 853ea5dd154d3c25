// Where a campaign's (or calibration's) runs and outputs are written, and the check that they can be, made
// before anything is registered in the store: a job that cannot write its folders stops before it starts.
#pragma once
#include <cstdint>
#include <string>

namespace flume::campaigns {

// "" when `name` can name a campaign (and so the folder "<db>.runs/<name>" and a results view), otherwise
// what is wrong: 1 to 64 characters from A-Z a-z 0-9 _ . -, and not "." or "..", which are folder links.
std::string campaign_name_problem(const std::string& name);

// The absolute folder holding the runs: `output_dir`, or "<db_file>.runs/<name>" when it is empty.
std::string runs_base_folder(const std::string& output_dir, const std::string& db_file, const std::string& name);
// "<base>/run-NNNNNN".
std::string run_folder(const std::string& base, std::int64_t index);

// Creates `folder` and checks that a file can be made in it; throws flume::InputError("<file>: <field>: ...")
// naming the folder and the reason otherwise.
void check_writable_folder(const std::string& folder, const std::string& file, const std::string& field);

}  // namespace flume::campaigns
