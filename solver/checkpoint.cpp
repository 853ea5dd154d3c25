#include "solver/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace flume {
namespace {

constexpr char kMagic[8] = {'F', 'L', 'U', 'M', 'E', 'C', 'K', 'P'};
constexpr uint32_t kVersion = 2;  // 2: pressure probes

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace

std::string checkpoint_scene_key(const std::string& source_json) {
  nlohmann::json j = nlohmann::json::parse(source_json);
  if (j.contains("solver") && j["solver"].is_object()) j["solver"].erase("end_time");
  return j.dump();  // objects keep their keys sorted: canonical
}

void write_checkpoint_file(const std::string& path, const std::string& scene_key, const std::string& payload) {
  StateArchive head;
  std::string key = scene_key;
  uint64_t size = payload.size(), sum = fnv1a(payload);
  head(key);
  head(size);
  head(sum);
  const std::string part = path + ".part";
  // Written and flushed to the disk before the rename, so that after a crash the name holds either the old
  // checkpoint or the whole new one, never a file the rename reached before its data.
  const int fd = ::open(part.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(part, "", std::string("cannot write the checkpoint: ") + std::strerror(errno));
  const auto put = [&](const char* p, size_t n) {
    while (n > 0) {
      const ssize_t w = ::write(fd, p, n);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        const std::string why = std::strerror(errno);
        ::close(fd);
        throw InputError(part, "", "cannot write the checkpoint: " + why);
      }
      p += w;
      n -= static_cast<size_t>(w);
    }
  };
  const uint32_t version = kVersion;
  put(kMagic, sizeof kMagic);
  put(reinterpret_cast<const char*>(&version), sizeof version);
  put(head.bytes().data(), head.bytes().size());
  put(payload.data(), payload.size());
  if (::fsync(fd) != 0 || ::close(fd) != 0)
    throw InputError(part, "", std::string("cannot write the checkpoint: ") + std::strerror(errno));
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  if (ec) throw InputError(path, "", "cannot replace the checkpoint: " + ec.message());
}

std::string read_checkpoint_file(const std::string& path, const std::string& scene_key) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "no checkpoint to resume from (run with --checkpoint-every first)");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string all = ss.str();
  if (all.size() < sizeof kMagic + sizeof(uint32_t) || all.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0)
    throw InputError(path, "", "is not a flume checkpoint");
  uint32_t version = 0;
  std::memcpy(&version, all.data() + sizeof kMagic, sizeof version);
  if (version != kVersion)
    throw InputError(path, "version", "checkpoint format " + std::to_string(version) + ", this build reads " +
                                          std::to_string(kVersion));
  const size_t prefix = sizeof kMagic + sizeof version;
  StateArchive head(all.substr(prefix), path);
  std::string key;
  uint64_t size = 0, sum = 0;
  head(key);
  head(size);
  head(sum);
  const size_t start = prefix + head.position();
  if (all.size() != start + size) throw InputError(path, "", "checkpoint truncated or padded");
  std::string payload = all.substr(start);
  if (fnv1a(payload) != sum) throw InputError(path, "", "checkpoint corrupt (checksum differs)");
  if (key != scene_key)
    throw InputError(path, "scene", "the checkpoint is of another scene or other settings (only solver.end_time "
                                    "may change on --resume)");
  return payload;
}

}  // namespace flume
