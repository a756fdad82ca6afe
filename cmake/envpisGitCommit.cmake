# SPDX-License-Identifier: Apache-2.0
# Writes OUT (a .cpp defining envpis::app::kBuildCommit) from TEMPLATE with the short commit hash of the
# source tree SOURCE_DIR, "+dirty" when tracked files differ from it, or "unknown" outside a git checkout
# or without git (GIT_EXECUTABLE empty). Run at every build (cmake -P, apps/envpis/CMakeLists.txt);
# configure_file leaves OUT untouched when the text is the same, so only a new commit recompiles it.
set(ENVPIS_BUILD_COMMIT "unknown")
if(GIT_EXECUTABLE)
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --short HEAD
                  OUTPUT_VARIABLE hash OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE failed ERROR_QUIET)
  if(NOT failed AND hash MATCHES "^[0-9a-f]+$")
    set(ENVPIS_BUILD_COMMIT "${hash}")
    # Untracked files do not count: build directories and scratch files inside the tree are not the code.
    execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" status --porcelain --untracked-files=no
                    OUTPUT_VARIABLE changes RESULT_VARIABLE failed ERROR_QUIET)
    if(NOT failed AND NOT changes STREQUAL "")
      string(APPEND ENVPIS_BUILD_COMMIT "+dirty")
    endif()
  endif()
endif()
configure_file("${TEMPLATE}" "${OUT}" @ONLY)
