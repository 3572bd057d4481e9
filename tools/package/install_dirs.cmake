# Install destinations (included by the top CMakeLists.txt before the folders'
# install rules).
#
# Programs and data go where GNUInstallDirs says, under the prefix given at
# install time: bin/, share/visvol/, share/doc/visvol/. The files of the
# system's own trees (the configuration, the systemd unit, the state
# directory) follow GNUInstallDirs' rule for a /usr prefix, decided when
# `cmake --install` or cpack runs (the prefix is only known then):
#
#   prefix      configuration      unit                  state
#   /usr        /etc/visvol/       /lib/systemd/system/  /var/lib/visvol/
#   P (other)   P/etc/visvol/      P/lib/systemd/system/ P/var/lib/visvol/
#
# /lib/systemd/system is where Debian 12's packages put units (its /usr is
# merged; dpkg keeps a file where the package says). The Debian package
# installs with the prefix /usr (tools/package/cpack.cmake).
include(GNUInstallDirs)

# visvol_install_system(etc|unit|state SUBDIR [FILES file...] [RENAME name])
# installs FILES (or, with none, an empty directory) into SUBDIR of the
# configuration, unit or state tree of the table above ("" for the tree
# itself). RENAME: the installed name of a single file.
function(visvol_install_system kind subdir)
  cmake_parse_arguments(I "" "RENAME" "FILES" ${ARGN})
  if(kind STREQUAL "etc")
    set(system_dir /etc)
    set(prefix_dir ${CMAKE_INSTALL_SYSCONFDIR})
  elseif(kind STREQUAL "unit")
    set(system_dir /lib/systemd/system)
    set(prefix_dir lib/systemd/system)
  elseif(kind STREQUAL "state")
    set(system_dir /var/lib)
    set(prefix_dir ${CMAKE_INSTALL_LOCALSTATEDIR}/lib)
  else()
    message(FATAL_ERROR "visvol_install_system: kind '${kind}' is not etc, unit or state")
  endif()
  if(subdir)
    string(PREPEND subdir "/")
  endif()
  set(files "")
  foreach(f IN LISTS I_FILES)
    get_filename_component(f "${f}" ABSOLUTE)
    string(APPEND files " \"${f}\"")
  endforeach()
  if(files)
    set(what "TYPE FILE FILES${files}")
    if(I_RENAME)
      string(APPEND what " RENAME \"${I_RENAME}\"")
    endif()
  else()
    # an empty directory: file(INSTALL) of the directory itself, without its contents
    set(what "TYPE DIRECTORY FILES \"${CMAKE_CURRENT_BINARY_DIR}/visvol_empty_dir/\"")
    file(MAKE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}/visvol_empty_dir")
  endif()
  # file(INSTALL) puts $DESTDIR in front of an absolute destination itself
  install(CODE "
    string(REGEX REPLACE \"/+$\" \"\" _visvol_prefix \"\${CMAKE_INSTALL_PREFIX}\")
    if(_visvol_prefix STREQUAL \"/usr\")
      set(_visvol_dir \"${system_dir}${subdir}\")
    else()
      set(_visvol_dir \"\${_visvol_prefix}/${prefix_dir}${subdir}\")
    endif()
    file(INSTALL DESTINATION \"\${_visvol_dir}\" ${what})
  ")
endfunction()
