# Writes OUT from IN with the commit of SOURCE_DIR, rewriting OUT only when
# its text changes (so a build after a commit recompiles one file, and a build
# without one recompiles nothing). Run at every build by base/CMakeLists.txt.
#   cmake -DIN=... -DOUT=... -DSOURCE_DIR=... -DVERSION=... -P version.cmake
set(VISVOL_VERSION_NUMBER "${VERSION}")
set(VISVOL_VERSION_COMMIT "unknown")
find_package(Git QUIET)
if(GIT_FOUND)
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --short=10 HEAD
                  OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
  if(rc EQUAL 0 AND commit)
    set(VISVOL_VERSION_COMMIT "${commit}")
    execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" status --porcelain --untracked-files=no
                    OUTPUT_VARIABLE changes ERROR_QUIET)
    if(changes)
      string(APPEND VISVOL_VERSION_COMMIT "-dirty")
    endif()
  endif()
endif()
configure_file("${IN}" "${OUT}.new" @ONLY)
file(READ "${OUT}.new" new_text)
set(old_text "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old_text)
endif()
if(NOT new_text STREQUAL old_text)
  file(RENAME "${OUT}.new" "${OUT}")
else()
  file(REMOVE "${OUT}.new")
endif()
