// Entry points of `flume campaign ...` and `flume model ...`.
#pragma once

namespace flume {
// flume campaign run SPEC --db FILE [--workers N] | status --db FILE | export --db FILE --csv OUT
int campaign_main(int argc, char** argv);
// flume model ishigami|test --out DIR [--set name=value ...]
int model_main(int argc, char** argv);
}  // namespace flume
