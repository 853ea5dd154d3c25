// One writer per campaign database, whatever path it is reached by: an exclusive flock(2) on the database file
// itself, so a symlink or a hard link to the same file meets the same lock. The kernel drops it when the holder
// exits or dies; it is advisory and never touches SQLite's own byte-range locks.
#pragma once
#include <string>

namespace flume::store {

class WriterLock {
 public:
  // Creates the file when it does not exist (SQLite takes an empty file as a new database). Throws
  // flume::InputError naming `db_file` when the file cannot be opened for writing, when its folder is not
  // writable (SQLite writes <db>-wal and <db>-shm beside it), or when another process holds the lock; the last
  // names the holder's pid when the kernel says it (/proc/locks).
  explicit WriterLock(const std::string& db_file);
  ~WriterLock();
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace flume::store
