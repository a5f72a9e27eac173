# Runs at every build (not at configure time): writes the commit the binary is built from,
# with a dirty flag when tracked files differ from it, into a small C++ source - rewritten
# only when the text changes, so an unchanged tree recompiles nothing.
#   cmake -DSOURCE_DIR=<repo> -DOUTPUT=<file.cpp> -P GitVersion.cmake
execute_process(COMMAND git rev-parse --short=12 HEAD WORKING_DIRECTORY "${SOURCE_DIR}"
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE commit_failed)
set(dirty "false")
if(commit_failed OR commit STREQUAL "")
  set(commit "")
else()
  # Tracked files only: build folders and other untracked files do not make code dirty.
  execute_process(COMMAND git status --porcelain --untracked-files=no WORKING_DIRECTORY "${SOURCE_DIR}"
                  OUTPUT_VARIABLE status OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(NOT status STREQUAL "")
    set(dirty "true")
  endif()
endif()
set(text "// Generated at build time by cmake/GitVersion.cmake: do not edit.
#include \"vsd/core/provenance.hpp\"

namespace vsd {
BuildProvenance buildProvenance() { return {\"${commit}\", ${dirty}}; }
}  // namespace vsd
")
set(old "")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUTPUT}" "${text}")
endif()
