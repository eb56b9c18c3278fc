# Install-time part of `cmake --install` (systemd/CMakeLists.txt passes the variables below): the
# unit, made from robocald.service.in with the paths of the prefix the install is made with, and
# the configuration in SYSCONFDIR/robocald. file(INSTALL) honours DESTDIR and lists every file in
# install_manifest.txt. A configuration file that exists and differs (an operator's edits) is
# kept; the new default is installed beside it as NAME.new.
# In: CMAKE_INSTALL_PREFIX, CMAKE_INSTALL_{SBINDIR,SYSCONFDIR,DOCDIR,LIBDIR} (relative, from
# configure time), ROBOCAL_SOURCE_DIR, ROBOCAL_UNIT_WORK_DIR (a folder of the build for the unit).
include(${CMAKE_CURRENT_LIST_DIR}/install-dirs.cmake)
robocal_install_dirs()

# A folder of its own per install, so that a `sudo cmake --install` leaves no root-owned file in
# the build for the next one to trip on.
string(RANDOM LENGTH 12 tag)
set(work "${ROBOCAL_UNIT_WORK_DIR}/unit-${tag}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/robocald.service.in ${work}/robocald.service @ONLY)
file(INSTALL ${work}/robocald.service DESTINATION "${CMAKE_INSTALL_PREFIX}/lib/systemd/system")
file(REMOVE_RECURSE "${work}")

foreach(name robocald.json drivers.json puma560.json cell.json)
  set(source "${ROBOCAL_SOURCE_DIR}/config/${name}")
  set(installed "$ENV{DESTDIR}${ROBOCALD_CONFIG_DIR}/${name}")
  if(EXISTS "${installed}")
    file(SHA256 "${installed}" installed_hash)
    file(SHA256 "${source}" source_hash)
    if(NOT installed_hash STREQUAL source_hash)
      message(STATUS "Keeping: ${installed} (edited); the new default is ${name}.new beside it")
      file(INSTALL "${source}" DESTINATION "${ROBOCALD_CONFIG_DIR}" RENAME "${name}.new")
      continue()
    endif()
  endif()
  file(INSTALL "${source}" DESTINATION "${ROBOCALD_CONFIG_DIR}")
endforeach()
