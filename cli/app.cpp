#include "cli/app.h"

#include <cstdio>
#include <string>
#include <vector>

#include "cli/registry.h"
#include "common/command.h"
#include "common/errors.h"
#include "common/version.h"
#include "solver/cpu_kernels.h"

namespace flume::cli {
namespace {

// A command that parses its own arguments: everything after its name is handed to its main.
void add_passthrough(CLI::App& sub, int (*main)(int, char**)) {
  sub.prefix_command();
  sub.set_help_flag();  // --help goes to the command itself
  CLI::App* self = &sub;
  on_parse(sub, [self, main] {
    std::vector<std::string> args = {self->get_name()};
    for (const std::string& a : self->remaining()) args.push_back(a);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    return main(static_cast<int>(args.size()), argv.data());
  });
}

// The deepest command given on the line ("run", "campaign export"), and its app.
const CLI::App* deepest(const CLI::App& app, std::string& path) {
  const CLI::App* at = &app;
  for (;;) {
    const auto subs = at->get_subcommands();
    if (subs.empty()) return at;
    at = subs.front();
    path += (path.empty() ? "" : " ") + at->get_name();
  }
}

std::string names_of_subcommands(const CLI::App& app) {
  std::string s;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    s += (s.empty() ? "" : ", ") + sub->get_name();
  return s;
}

int usage_error(const std::string& path, const std::string& message) {
  const std::string cmd = path.empty() ? "flume" : "flume " + path;
  std::fprintf(stderr, "%s: %s (see '%s --help')\n", cmd.c_str(), message.c_str(), cmd.c_str());
  return kExitInvalidInput;
}

// CLI11's own words, in the "option: problem" order of the rest of flume's messages.
std::string reworded(const CLI::ParseError& e) {
  std::string m = e.what();
  const std::string required = " is required";
  if (e.get_name() == "RequiredError" && m.size() > required.size() &&
      m.compare(m.size() - required.size(), required.size(), required) == 0)
    m = m.substr(0, m.size() - required.size()) + ": is required";
  return m;
}

}  // namespace

std::unique_ptr<CLI::App> build_app() {
  auto app = std::make_unique<CLI::App>("flume: tsunami-debris flume simulation and uncertainty campaigns", "flume");
  std::string kernels;  // the CPU loops' instruction set on this machine (solver/cpu_kernels.h)
  try {
    kernels = std::string(", ") + cpu_kernels_name(cpu_kernels()) + " CPU kernels";
  } catch (const InputError& e) {
    kernels = std::string(", ") + e.what();
  }
  app->set_version_flag("--version", std::string("flume ") + build_info::version() + " (" +
                                         build_info::commit() + ", " + build_info::kind() + " build" + kernels + ")");
  app->allow_extras();  // unknown options are reported by run() in flume's words; subcommands inherit this
  app->require_subcommand(0, 1);
  for (const Command& c : commands()) {
    CLI::App* sub = app->add_subcommand(c.name, c.summary);
    if (c.add) c.add(*sub);
    else add_passthrough(*sub, c.main);
  }
  return app;
}

int run(int argc, char** argv) {
  const auto app = build_app();
  chosen_action() = nullptr;
  std::string path;
  try {
    app->parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app->exit(e);  // --help, --version
    deepest(*app, path);
    return usage_error(path, reworded(e));
  }
  const CLI::App* at = deepest(*app, path);
  if (!chosen_action()) {
    const std::vector<std::string> extras = at->remaining();
    if (!extras.empty() && extras.front().rfind('-', 0) != 0)
      return usage_error(path, extras.front() + ": unknown command (one of: " + names_of_subcommands(*at) + ")");
    return usage_error(path, "needs a command: one of " + names_of_subcommands(*at));
  }
  // A command that parses its own arguments gets them all (add_passthrough); the others may have no extras.
  for (const CLI::App* a = at->get_prefix_command() ? nullptr : at; a; a = a->get_parent()) {
    const std::vector<std::string> extras = a->remaining();
    if (extras.empty()) continue;
    const std::string& x = extras.front();
    return usage_error(path, x + (x.rfind('-', 0) == 0 ? ": unknown option" : ": unexpected argument"));
  }
  const std::string cmd = "flume " + path;
  try {
    return chosen_action()();
  } catch (const UsageError& e) {
    return usage_error(path, e.what());
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: %s\n", cmd.c_str(), e.what());
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: internal error: %s\n", cmd.c_str(), e.what());
    return kExitInternal;
  }
}

}  // namespace flume::cli
