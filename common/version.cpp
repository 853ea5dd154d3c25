#include "common/version.h"

#include "flume_version.h"

namespace flume::build_info {

const char* version() { return FLUME_VERSION; }
const char* commit() { return FLUME_GIT_VERSION; }
const char* kind() { return FLUME_BUILD_KIND; }
std::string version_and_commit() { return std::string(FLUME_VERSION) + " (" + FLUME_GIT_VERSION + ")"; }

}  // namespace flume::build_info
