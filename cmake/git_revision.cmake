# Run at every build (cmake -P): writes OUTPUT with the source tree's git revision as it is now, "-dirty" when
# tracked files differ from HEAD, "unknown" without git. configure_file rewrites OUTPUT only when the text changes,
# so an unchanged revision recompiles nothing. Results then name the revision the binary was built from, not the
# one its source folder happens to hold when it runs (a binary carried to another machine reports its own).
execute_process(COMMAND git -C "${SOURCE_DIR}" rev-parse --short HEAD
                OUTPUT_VARIABLE revision OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
if(failed OR revision STREQUAL "")
  set(revision "unknown")
else()
  execute_process(COMMAND git -C "${SOURCE_DIR}" status --porcelain --untracked-files=no
                  OUTPUT_VARIABLE changes OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(NOT changes STREQUAL "")
    string(APPEND revision "-dirty")
  endif()
endif()
set(CCDBENCH_GIT_REVISION "${revision}")
configure_file("${SOURCE_DIR}/cmake/git_revision.hpp.in" "${OUTPUT}" @ONLY)
