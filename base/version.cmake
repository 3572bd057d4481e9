# Writes OUT from IN with the commit of SOURCE_DIR, rewriting OUT only when
# its text changes (so a build after a commit recompiles one file, and a build
# without one recompiles nothing). Run at every build by base/CMakeLists.txt.
#   cmake -DIN=... -DOUT=... -DSOURCE_DIR=... -DVERSION=... -P version.cmake
set(VISVOL_VERSION_NUMBER "${VERSION}")
set(VISVOL_VERSION_COMMIT "unknown")
find_package(Git QUIET)
if(GIT_FOUND)
  # only this project's own checkout (a tarball unpacked inside another
  # repository must not take that one's commit)
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --show-toplevel
                  OUTPUT_VARIABLE top OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc_top)
  get_filename_component(top "${top}" REALPATH)
  get_filename_component(here "${SOURCE_DIR}" REALPATH)
  set(rc 1)
  if(rc_top EQUAL 0 AND top STREQUAL here)
    execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --short=10 HEAD
                    OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
  endif()
  if(rc EQUAL 0 AND commit)
    set(VISVOL_VERSION_COMMIT "${commit}")
    # --no-optional-locks: a build never takes the index lock from a user's git
    execute_process(COMMAND "${GIT_EXECUTABLE}" --no-optional-locks -C "${SOURCE_DIR}" status --porcelain
                            --untracked-files=no
                    OUTPUT_VARIABLE changes ERROR_QUIET RESULT_VARIABLE rc_status)
    if(changes OR NOT rc_status EQUAL 0)
      string(APPEND VISVOL_VERSION_COMMIT "-dirty")
    endif()
  endif()
endif()
# not a checkout of its own: what a packager building from a tarball gives
# (-DVISVOL_COMMIT=..., a hexadecimal commit)
if(VISVOL_VERSION_COMMIT STREQUAL "unknown" AND COMMIT)
  if(NOT COMMIT MATCHES "^[0-9a-f]+$")
    message(FATAL_ERROR "VISVOL_COMMIT '${COMMIT}' is not a hexadecimal commit")
  endif()
  set(VISVOL_VERSION_COMMIT "${COMMIT}")
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
