// Test helpers shared by the command-line tests: start a program with stdin from /dev/null and stdout and stderr
// to files, wait for it with a time limit, and run it to completion returning its exit code (128 + signal when
// killed) with what it wrote.
#pragma once
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace flume::test {

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The child's pid, or -1 when it could not be started.
inline pid_t spawn(const std::vector<std::string>& args, const std::filesystem::path& out,
                   const std::filesystem::path& err) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return rc == 0 ? pid : -1;
}

// Exit code, or 128 + signal; kills the process and returns -1 past the timeout.
inline int wait_for(pid_t pid, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (std::chrono::steady_clock::now() > end) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

struct CommandResult {
  int rc = -1;  // -1: not started, or killed at the time limit
  std::string out, err;
};

// Runs the command with its output in dir/cmd.out and dir/cmd.err.
inline CommandResult run_command(const std::vector<std::string>& args, const std::filesystem::path& dir,
                                 double timeout_s = 600) {
  const std::filesystem::path out = dir / "cmd.out", err = dir / "cmd.err";
  CommandResult r;
  const pid_t pid = spawn(args, out, err);
  if (pid > 0) r.rc = wait_for(pid, timeout_s);
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

}  // namespace flume::test
