// `flume debris-paths RUN_DIR ... --out FILE.svg`: top-down debris paths of finished runs (report/paths.cpp).
#pragma once

namespace flume::report {

int debris_paths_main(int argc, char** argv);

}  // namespace flume::report
