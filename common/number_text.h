// Numbers in text files (CSV exports): the shortest text that reads back to the same double (%.17g prints 0.2
// as 0.20000000000000001).
#pragma once
#include <cstdio>
#include <cstdlib>
#include <string>

namespace flume {

inline std::string round_trip_text(double v) {
  char buf[32];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

}  // namespace flume
