// `flume campaign run|status|export` and `flume model` on the command line (common/command.h).
#pragma once

namespace CLI {
class App;
}

namespace flume {
void add_campaign_command(CLI::App& app);
// analytic stand-ins for `flume run` (campaigns/models.cpp)
void add_model_command(CLI::App& app);
}  // namespace flume
