# The Debian package of the programs (included by the top CMakeLists.txt in the
# optimised tree). In a built tree:
#   cpack --config BUILD/CPackConfig.cmake -B DIR    DIR/visvol_VERSION_ARCH.deb
# It holds what `cmake --install` lays out, with the prefix /usr (see
# install_dirs.cmake): /usr/bin/visvol-console, visvol, visvol-echo,
# visvol-hapticsim; /usr/share/visvol/; /usr/share/doc/visvol/examples/;
# /lib/systemd/system/visvol-console.service; /etc/visvol/console.toml (a
# conffile); /var/lib/visvol/terrains/. Its maintainer scripts (debian/) make
# the visvol user, own the state directories to it and tell systemd; nothing
# enables or starts the service. Debian 12 (dpkg 1.21, apt 2.6) reads zstd.
set(VISVOL_PACKAGE_MAINTAINER "visvol maintainers <visvol@localhost>" CACHE STRING
    "Maintainer field of the Debian package")
set(VISVOL_PACKAGE_HOMEPAGE "" CACHE STRING "Homepage field of the Debian package (none when empty)")

set(CPACK_GENERATOR DEB)
set(CPACK_VERBATIM_VARIABLES ON)  # the values below written to CPackConfig.cmake as they are
set(CPACK_PACKAGE_NAME visvol)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${VISVOL_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "visibility volumes and a real-time console for flight-path planning")
# The long description (cpack puts the summary above it and indents it as
# Debian's control file wants).
set(CPACK_PACKAGE_DESCRIPTION "visvol-console runs a force-directed rope and a haptic device's servo at
1 kHz in a precomputed visibility field (a field pack), publishes the path
over DDS and takes commands; a systemd unit (Type=notify, watchdog) runs it
as the visvol user from /etc/visvol/console.toml. visvol builds the packs
from DEMs and plans, checks and draws paths offline; visvol-echo and
visvol-hapticsim talk to a console over DDS and play a haptic device on a
CAN interface.")
if(VISVOL_PACKAGE_HOMEPAGE)
  set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "${VISVOL_PACKAGE_HOMEPAGE}")
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # visvol_0.1.0_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Depends: the shared libraries' packages as dpkg-shlibdeps finds them
# (dpkg-dev, file), and adduser for postinst.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_COMPRESSION_TYPE zstd)
# Installed with DESTDIR under the prefix /usr, so that install_dirs.cmake's
# /usr rule puts the configuration in /etc and the unit in /lib/systemd/system.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(_debian ${CMAKE_CURRENT_LIST_DIR}/debian)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    "${_debian}/conffiles;${_debian}/postinst;${_debian}/prerm;${_debian}/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)  # scripts 0755, conffiles 0644
# `cpack --config BUILD/CPackSourceConfig.cmake`: the sources without build trees or outputs.
set(CPACK_SOURCE_GENERATOR TGZ)
set(CPACK_SOURCE_IGNORE_FILES "/\\.git/" "/build/" "/build-[^/]*/" "/out/" "\\.tmp\\.")
include(CPack)
