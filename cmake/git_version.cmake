# Writes the version header OUT from IN with the commit `git describe` names now. Run at configure time and, by
# the target flume_version_header, at every build: a binary built after a pull or a commit names the commit it
# was built from (run.json, result.h5, reports, `flume --version`), not the one the build was configured at.
# configure_file leaves OUT untouched when its text is unchanged, so only a new commit recompiles its includers.
# Inputs: SOURCE_DIR, IN, OUT, PROJECT_VERSION, FLUME_BUILD_KIND.
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE FLUME_GIT_VERSION OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT FLUME_GIT_VERSION)
  set(FLUME_GIT_VERSION "unknown")
endif()
configure_file(${IN} ${OUT} @ONLY)
