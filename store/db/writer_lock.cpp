#include "store/db/writer_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/errors.h"

namespace flume::store {
namespace {

// The pid holding a flock on the file (device, inode), from /proc/locks; 0 when unknown.
long flock_holder(const struct stat& st) {
  std::ifstream locks("/proc/locks");
  std::string line;
  char want[64];
  std::snprintf(want, sizeof want, "%02x:%02x:%llu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long long>(st.st_ino));
  while (std::getline(locks, line)) {
    // "1: FLOCK  ADVISORY  WRITE 12345 08:01:5678 0 EOF"
    std::istringstream in(line);
    std::string number, kind, mode, access, pid, id;
    if (!(in >> number >> kind >> mode >> access >> pid >> id)) continue;
    if (kind == "FLOCK" && access == "WRITE" && id == want) return std::atol(pid.c_str());
  }
  return 0;
}

}  // namespace

WriterLock::WriterLock(const std::string& db_file) {
  namespace fs = std::filesystem;
  fd_ = open(db_file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw InputError(db_file, "", std::string("cannot open the campaign database for writing: ") +
                                      std::strerror(errno));
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    struct stat st {};
    const long pid = fstat(fd_, &st) == 0 ? flock_holder(st) : 0;
    close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK)
      throw InputError(db_file, "", std::string("cannot lock the campaign database: ") + std::strerror(err));
    throw InputError(db_file, "",
                     "another flume job" + (pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string()) +
                         " is writing this database (through this or another path to the same file); wait for "
                         "it or stop it");
  }
  // SQLite keeps its journal beside the file it resolved (symlinks followed): that folder must be writable.
  std::error_code ec;
  const fs::path real = fs::canonical(db_file, ec);
  const fs::path folder = ec ? fs::path(db_file).parent_path() : real.parent_path();
  if (access(folder.empty() ? "." : folder.c_str(), W_OK | X_OK) != 0) {
    const int err = errno;
    close(fd_);
    fd_ = -1;
    throw InputError(db_file, "",
                     "the folder " + (folder.empty() ? std::string(".") : folder.string()) +
                         " is not writable (" + std::strerror(err) +
                         "); SQLite writes the database's -wal and -shm files there");
  }
}

WriterLock::~WriterLock() {
  if (fd_ >= 0) close(fd_);
}

}  // namespace flume::store
