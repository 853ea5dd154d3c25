// Wall-clock durations as people read them in progress lines and summaries.
#pragma once
#include <cstdio>
#include <string>

namespace flume {

// "m:ss" under an hour, "h:mm:ss" above, "unknown" for a negative or absurd value (no estimate yet).
inline std::string hms(double s) {
  if (!(s >= 0) || s > 1e9) return "unknown";
  const long t = static_cast<long>(s + 0.5);
  char buf[32];
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  return buf;
}

}  // namespace flume
