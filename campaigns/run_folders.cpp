#include "campaigns/run_folders.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "common/errors.h"

namespace flume::campaigns {

namespace fs = std::filesystem;

std::string campaign_name_problem(const std::string& name) {
  if (name.empty() || name.size() > 64 ||
      name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") != std::string::npos)
    return "must be 1 to 64 characters from A-Z a-z 0-9 _ . - (got '" + name + "')";
  if (name == "." || name == "..")
    return "must not be '" + name + "': the name is also the folder of its runs, and '" + name +
           "' would put them beside the database";
  return "";
}

std::string runs_base_folder(const std::string& output_dir, const std::string& db_file, const std::string& name) {
  fs::path base = output_dir.empty() ? fs::path(db_file + ".runs") / name : fs::path(output_dir);
  std::error_code ec;
  const fs::path absolute = fs::absolute(base, ec);
  return (ec ? base : absolute).lexically_normal().string();
}

std::string run_folder(const std::string& base, std::int64_t index) {
  char leaf[32];
  std::snprintf(leaf, sizeof leaf, "run-%06lld", static_cast<long long>(index));
  return (fs::path(base) / leaf).string();
}

void check_writable_folder(const std::string& folder, const std::string& file, const std::string& field) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(file, field, "cannot create the folder " + folder + ": " + ec.message());
  if (!fs::is_directory(folder, ec)) throw InputError(file, field, folder + " is not a folder");
  // access() says yes to root on a read-only mount: making a file is the real test.
  std::string probe = (fs::path(folder) / ".flume-write-check-XXXXXX").string();
  const int fd = mkstemp(probe.data());
  if (fd < 0)
    throw InputError(file, field, "cannot write in the folder " + folder + ": " + std::strerror(errno));
  close(fd);
  unlink(probe.c_str());
}

}  // namespace flume::campaigns
