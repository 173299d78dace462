# Runs inside `cmake --install` / CPack (install(CODE) in systemd/CMakeLists.txt), when the real
# prefix is known: writes handtrackd.service and handtrack-ws.service with the programs' and the
# configuration's actual paths and the shared sandbox, and installs the default configuration without overwriting a changed one.
#
# In: CMAKE_INSTALL_PREFIX (the install-time prefix), HANDTRACK_SERVICE_IN,
# HANDTRACK_WS_SERVICE_IN, HANDTRACK_SANDBOX_INC, HANDTRACK_DEFAULT_CONFIG, HANDTRACK_STAGE_DIR,
# HANDTRACK_REL_{BINDIR,SBINDIR,SYSCONFDIR,DOCDIR,UNITDIR}.

function(handtrack_abs out rel)
  if(IS_ABSOLUTE "${rel}")
    set(${out} "${rel}" PARENT_SCOPE)
  else()
    set(${out} "${CMAKE_INSTALL_PREFIX}/${rel}" PARENT_SCOPE)
  endif()
endfunction()

# /etc for the system prefixes, as GNUInstallDirs does (FHS: /usr is read-only, /etc per host).
if(IS_ABSOLUTE "${HANDTRACK_REL_SYSCONFDIR}")
  set(sysconfdir "${HANDTRACK_REL_SYSCONFDIR}")
elseif(CMAKE_INSTALL_PREFIX STREQUAL "/usr" OR CMAKE_INSTALL_PREFIX STREQUAL "/")
  set(sysconfdir "/etc")
elseif(CMAKE_INSTALL_PREFIX MATCHES "^/opt/")
  set(sysconfdir "/etc${CMAKE_INSTALL_PREFIX}")
else()
  set(sysconfdir "${CMAKE_INSTALL_PREFIX}/${HANDTRACK_REL_SYSCONFDIR}")
endif()
set(HANDTRACK_CONFDIR "${sysconfdir}/handtrack")
handtrack_abs(HANDTRACK_SBINDIR "${HANDTRACK_REL_SBINDIR}")
handtrack_abs(HANDTRACK_BINDIR "${HANDTRACK_REL_BINDIR}")
handtrack_abs(HANDTRACK_DOCDIR "${HANDTRACK_REL_DOCDIR}")
handtrack_abs(unitdir "${HANDTRACK_REL_UNITDIR}")

file(READ "${HANDTRACK_SANDBOX_INC}" HANDTRACK_SANDBOX)
string(STRIP "${HANDTRACK_SANDBOX}" HANDTRACK_SANDBOX)
configure_file("${HANDTRACK_SERVICE_IN}" "${HANDTRACK_STAGE_DIR}/handtrackd.service" @ONLY)
configure_file("${HANDTRACK_WS_SERVICE_IN}" "${HANDTRACK_STAGE_DIR}/handtrack-ws.service" @ONLY)
file(INSTALL DESTINATION "${unitdir}" TYPE FILE FILES "${HANDTRACK_STAGE_DIR}/handtrackd.service"
  "${HANDTRACK_STAGE_DIR}/handtrack-ws.service")

# The configuration is the administrator's once installed (a conffile in the .deb): a changed
# file stays and the new default goes next to it as handtrackd.toml.new.
set(config "$ENV{DESTDIR}${HANDTRACK_CONFDIR}/handtrackd.toml")
if(EXISTS "${config}")
  file(READ "${config}" installed_text)
  file(READ "${HANDTRACK_DEFAULT_CONFIG}" default_text)
  if(NOT installed_text STREQUAL default_text)
    message(STATUS "Keeping changed ${config}; the default goes to handtrackd.toml.new")
    file(INSTALL DESTINATION "${HANDTRACK_CONFDIR}" TYPE FILE RENAME handtrackd.toml.new
      FILES "${HANDTRACK_DEFAULT_CONFIG}")
    return()
  endif()
endif()
file(INSTALL DESTINATION "${HANDTRACK_CONFDIR}" TYPE FILE FILES "${HANDTRACK_DEFAULT_CONFIG}")
