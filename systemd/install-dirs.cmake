# The absolute install paths of the unit and the configuration, from the prefix in
# CMAKE_INSTALL_PREFIX when this runs, by GNUInstallDirs' rules (prefix /usr: /etc; /opt/X:
# /etc/opt/X; any other: PREFIX/etc; absolute CMAKE_INSTALL_* kept as they are). Included at
# configure time, for the unit the tests verify, and at install time (systemd/install.cmake), where
# `cmake --install --prefix P` has set the prefix. Needs the relative CMAKE_INSTALL_SBINDIR,
# _SYSCONFDIR, _DOCDIR and _LIBDIR.

# Sets ROBOCALD_PROGRAM, ROBOCALD_CONFIG_DIR, ROBOCALD_CONFIG_FILE and ROBOCAL_DOC_DIR in the
# caller's scope.
function(robocal_install_dirs)
  if(NOT COMMAND GNUInstallDirs_get_absolute_install_dir)
    include(GNUInstallDirs)  # in an install script; CMAKE_INSTALL_LIBDIR set keeps it quiet
  endif()
  GNUInstallDirs_get_absolute_install_dir(sbindir CMAKE_INSTALL_SBINDIR SBINDIR)
  GNUInstallDirs_get_absolute_install_dir(sysconfdir CMAKE_INSTALL_SYSCONFDIR SYSCONFDIR)
  GNUInstallDirs_get_absolute_install_dir(docdir CMAKE_INSTALL_DOCDIR DOCDIR)
  set(ROBOCALD_PROGRAM "${sbindir}/robocald" PARENT_SCOPE)
  set(ROBOCALD_CONFIG_DIR "${sysconfdir}/robocald" PARENT_SCOPE)
  set(ROBOCALD_CONFIG_FILE "${sysconfdir}/robocald/robocald.json" PARENT_SCOPE)
  set(ROBOCAL_DOC_DIR "${docdir}" PARENT_SCOPE)
endfunction()
