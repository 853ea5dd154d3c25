// What this binary was built from, for the provenance every output carries (run.json, result.h5, the store,
// reports, `flume --version`). Defined in version.cpp, the one file that includes the generated header, so
// that a new commit recompiles one file (cmake/git_version.cmake regenerates the header at every build).
#pragma once
#include <string>

namespace flume::build_info {

const char* version();             // the project's version, "0.1.0"
const char* commit();              // `git describe --always --dirty --tags` at build time, or "unknown"
const char* kind();                // "portable" or "native (-march=native)"
std::string version_and_commit();  // "0.1.0 (660f7f8)"

}  // namespace flume::build_info
