// `flume debris-paths RUN_DIR ... --out FILE.svg`: top-down debris paths of finished runs (report/paths.cpp).
#pragma once

namespace CLI {
class App;
}

namespace flume::report {

void add_debris_paths_command(CLI::App& app);

}  // namespace flume::report
