// Error types shared by every layer, and the process exit codes they map to.
#pragma once
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

namespace flume {

// Exit codes of every `flume` command (the contract campaigns rely on).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,
  kExitInvalidInput = 2,
  kExitUnstable = 3,
  // 128 + N: stopped by signal N. `flume run` stopped by SIGINT (130) or SIGTERM (143) first writes result.h5
  // and run.json with status "killed" (solver/run.h); a campaign puts such a run back to pending.
};

// Bad user input: a malformed scene or spec, an out-of-range value, a missing file.
// what() is one line: "<file>: <field.path>: <what is wrong and what is allowed>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& field, const std::string& problem)
      : std::runtime_error(compose(file, field, problem)), file_(file), field_(field), problem_(problem) {}
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& problem() const { return problem_; }

 private:
  static std::string compose(const std::string& file, const std::string& field, const std::string& problem) {
    std::string s = file.empty() ? std::string("<input>") : file;
    if (!field.empty()) s += ": " + field;
    return s + ": " + problem;
  }
  std::string file_, field_, problem_;
};

// A command's main: runs `body` and turns what it throws into the exit code, an InputError printed with the
// usage (kExitInvalidInput), anything else as "<cli>: internal error: ..." (kExitInternal).
template <class Body>
int guarded_main(const char* cli, const char* usage, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::fputs(usage, stderr);
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", cli, e.what());
    return kExitInternal;
  }
}

}  // namespace flume
