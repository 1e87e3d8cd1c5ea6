# install.cmake: what `cmake --install` puts where on the rig computer, and the Debian package
# (`make package`, CPack's DEB generator) made from the same rules. Included by the top-level
# CMakeLists after every folder, so the programs' targets exist. docs/install.md is the user's view.
#
#   PREFIX/bin/                        ribbond ribbonctl ribbon-sim ribbon-grblsim ribbon-mbsim
#                                      ribbon-store-bench
#   PREFIX/share/ribbon/               the example rig files; scenes/ and maps/ (Modbus register
#                                      maps) beside them (rig files find both relative to their
#                                      own directory)
#   PREFIX/lib/systemd/system/         ribbond.service, its ExecStart and Documentation pointed at
#                                      PREFIX (installed, never enabled)
#   PREFIX/lib/sysusers.d/ribbon.conf  the unit's user `ribbon` (groups dialout, video)
#   PREFIX/share/doc/ribbon/           README.md and docs/
# The unit reads /etc/ribbon/rig.ini and writes only /var/lib/ribbon: neither is installed, the
# lab writes its own rig file (docs/install.md).

include(GNUInstallDirs)

set(RIBBON_PROGRAMS ribbond ribbonctl ribbon-sim ribbon-grblsim ribbon-mbsim ribbon-store-bench)
foreach(program ${RIBBON_PROGRAMS})
  if(TARGET ${program})
    install(TARGETS ${program} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

set(RIBBON_SHARE_DIR ${CMAKE_INSTALL_DATADIR}/ribbon)
set(RIBBON_DOC_DIR ${CMAKE_INSTALL_DATADIR}/doc/ribbon) # the unit's Documentation= names it
install(FILES
  ${CMAKE_SOURCE_DIR}/config/mock.ini
  ${CMAKE_SOURCE_DIR}/config/replay.ini
  ${CMAKE_SOURCE_DIR}/config/rig-gcode.ini
  ${CMAKE_SOURCE_DIR}/config/rig-modbus.ini
  DESTINATION ${RIBBON_SHARE_DIR})
install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/scenes DESTINATION ${RIBBON_SHARE_DIR}
        FILES_MATCHING PATTERN "*.ini")
install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/maps DESTINATION ${RIBBON_SHARE_DIR}
        FILES_MATCHING PATTERN "*.ini")

install(FILES ${CMAKE_SOURCE_DIR}/README.md DESTINATION ${RIBBON_DOC_DIR})
install(DIRECTORY ${CMAKE_SOURCE_DIR}/docs/ DESTINATION ${RIBBON_DOC_DIR}/docs)

# The unit in the tree names /usr/local (the default prefix); the installed copy names the prefix
# it is installed under, which is known only at install time (cmake --install --prefix, or CPack's
# /usr), hence install(CODE). systemd looks in PREFIX/lib/systemd/system for /usr and /usr/local.
install(CODE "
  set(unit_dir \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/system\")
  file(READ \"${CMAKE_SOURCE_DIR}/config/ribbond.service\" unit)
  string(REPLACE \"/usr/local/\" \"\${CMAKE_INSTALL_PREFIX}/\" unit \"\${unit}\")
  message(STATUS \"Installing: \${unit_dir}/ribbond.service\")
  file(MAKE_DIRECTORY \"\${unit_dir}\")
  file(WRITE \"\${unit_dir}/ribbond.service\" \"\${unit}\")
")
install(FILES ${CMAKE_SOURCE_DIR}/config/ribbon-sysusers.conf
        DESTINATION lib/sysusers.d RENAME ribbon.conf)

# --- the Debian package: `make package` (cpack -G DEB in the build directory).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ribbon-rig)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "snap-through trials on folded elastic ribbons: rig daemon, simulator, tracker, store")
set(CPACK_PACKAGE_CONTACT "Ribbon rig maintainers <ribbon-rig@localhost>")
# Install with DESTDIR into the staging directory and CMAKE_INSTALL_PREFIX = /usr (whatever the
# build's own prefix), so the unit's install(CODE) above writes /usr/bin/ribbond into ExecStart,
# not a staging path.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# The runtime libraries the programs link (readelf -d NEEDED, then dpkg -S on each), never the
# -dev packages; plplot-driver-cairo is PLplot's PNG driver, loaded at run time.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libc6, libstdc++6, libgcc-s1, \
libgsl27, libsqlite3-0, libserialport0, libmodbus5, libinih1, libmicrohttpd12, libjansson4, \
libcurl4, libsystemd0, libplplot17, plplot-driver-cairo, libjpeg62-turbo, libjs-chart.js, \
libopencv-core406, libopencv-imgproc406, libopencv-imgcodecs406, libopencv-videoio406, \
libopencv-calib3d406, libavcodec59, libavformat59, libavutil57")
# No maintainer scripts: the unit is installed disabled and nothing is started or enabled.
include(CPack)
