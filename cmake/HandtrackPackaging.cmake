# The Debian package (docs/SERVICE.md):  cd build && cpack -G DEB
# One package, `handtrack`, with everything `cmake --install` puts under prefix /usr: daemon,
# tools, client library + headers + CMake package + pkg-config file, Python module, unit, udev
# rules, sysusers/tmpfiles entries, /etc/handtrack/handtrackd.toml (a conffile) and the model.
set(CPACK_GENERATOR "DEB" CACHE STRING "CPack generators")
set(CPACK_PACKAGE_NAME "handtrack")
set(CPACK_PACKAGE_VENDOR "handtrack")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION "handtrackd tracks a hand, finger joints included, from one depth camera \
(OpenNI2) and publishes the poses into POSIX shared memory; C, C++ and Python clients read them.")
set(CPACK_PACKAGE_CONTACT "handtrack developers <handtrack@localhost>")
# Install with DESTDIR into the staging tree and prefix /usr, so the absolute /etc destination of
# the configuration lands in the package (install_service_files.cmake) and ExecStart= is /usr/sbin.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX "/usr")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "misc")
set(CPACK_DEBIAN_PACKAGE_PRIORITY "optional")
# Library dependencies (libOpenNI2, libsystemd, libpng, libstdc++ ...) from dpkg-shlibdeps.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# postinst falls back to groupadd/useradd (passwd) without systemd-sysusers.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "passwd")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "systemd, udev, python3")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  "${PROJECT_SOURCE_DIR}/systemd/debian/postinst"
  "${PROJECT_SOURCE_DIR}/systemd/debian/prerm"
  "${PROJECT_SOURCE_DIR}/systemd/debian/postrm"
  "${PROJECT_SOURCE_DIR}/systemd/debian/conffiles"
  "${PROJECT_SOURCE_DIR}/systemd/debian/triggers")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)
include(CPack)
