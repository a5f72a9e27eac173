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
# Per module (src/<m> and include/vsd/<m>): the git tree ids of its code at HEAD plus, when
# it has uncommitted changes, a hash of their diff - so a cache can tell which modules' code
# changed between two builds (experiment artefacts are rebuilt only when theirs did).
set(module_entries "")
if(NOT commit STREQUAL "")
  file(GLOB module_dirs LIST_DIRECTORIES true RELATIVE "${SOURCE_DIR}/src" "${SOURCE_DIR}/src/*")
  foreach(module IN LISTS module_dirs)
    if(NOT IS_DIRECTORY "${SOURCE_DIR}/src/${module}")
      continue()
    endif()
    set(identity "")
    foreach(tree IN ITEMS "src/${module}" "include/vsd/${module}")
      execute_process(COMMAND git rev-parse --short=12 "HEAD:${tree}" WORKING_DIRECTORY "${SOURCE_DIR}"
                      OUTPUT_VARIABLE tree_id OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
      string(APPEND identity "${tree_id}/")
    endforeach()
    execute_process(COMMAND git diff HEAD -- "src/${module}" "include/vsd/${module}" WORKING_DIRECTORY "${SOURCE_DIR}"
                    OUTPUT_VARIABLE module_diff ERROR_QUIET)
    if(NOT module_diff STREQUAL "")
      string(SHA256 diff_hash "${module_diff}")
      string(SUBSTRING "${diff_hash}" 0 12 diff_hash)
      string(APPEND identity "dirty-${diff_hash}")
    endif()
    string(APPEND module_entries "      {\"${module}\", \"${identity}\"},\n")
  endforeach()
endif()
set(text "// Generated at build time by cmake/GitVersion.cmake: do not edit.
#include \"vsd/core/provenance.hpp\"

namespace vsd {
BuildProvenance buildProvenance() {
  return {\"${commit}\", ${dirty},
    {
${module_entries}    }};
}
}  // namespace vsd
")
set(old "")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUTPUT}" "${text}")
endif()
