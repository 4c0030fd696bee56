# Install, export and package (a library for CAM posts).
#
#   cmake --install build --prefix PREFIX   bin/rotacal, the static libraries a post-processor
#                                           links, their headers under include/rotacal/ (core/...,
#                                           gcode/..., controllers/..., postproc/...), and
#                                           lib/cmake/rotacal/rotacalConfig.cmake: in a consumer,
#                                           find_package(rotacal) gives rotacal::core,
#                                           rotacal::gcode, rotacal::controllers, rotacal::postproc.
#   cpack -G DEB (in the build dir)         rotacal_<version>_<arch>.deb: the command-line tool;
#                                           rotacal-dev_<version>_<arch>.deb: libraries, headers,
#                                           CMake package.
# Two install components keep the tool's package free of the build dependencies: `runtime`
# (the executable) and `development` (the rest). scripts/package-check.sh proves both.
include(CMakePackageConfigHelpers)

# Exported as rotacal::<name>, the names the build already uses as aliases. postproc links
# controllers and gcode publicly, so all four are exported; report, history and cycles stay
# private to the tool.
set(rotacal_exported_libraries rotacal_core rotacal_gcode rotacal_controllers rotacal_postproc)
# Position-independent code: a post is often a plugin (a shared library the CAM system loads), and
# objects compiled for an executable (Debian's default PIE) cannot be linked into one.
foreach(lib ${rotacal_exported_libraries})
  string(REPLACE "rotacal_" "" export_name ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${export_name} POSITION_INDEPENDENT_CODE ON)
endforeach()

install(TARGETS rotacal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(TARGETS ${rotacal_exported_libraries} EXPORT rotacalTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
# The headers keep their paths relative to the source root: they include each other as
# "core/x.hpp". Every header of the four folders is installed (a new one needs no line here).
foreach(dir core gcode controllers postproc)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rotacal/${dir}
    COMPONENT development FILES_MATCHING PATTERN "*.hpp")
endforeach()

set(rotacal_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/rotacal)
install(EXPORT rotacalTargets NAMESPACE rotacal:: DESTINATION ${rotacal_cmake_dir} COMPONENT development)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rotacalConfig.cmake.in
  ${PROJECT_BINARY_DIR}/rotacalConfig.cmake INSTALL_DESTINATION ${rotacal_cmake_dir})
# 0.x: SameMajorVersion treats every 0.y as compatible with every other; the API is young, so a
# consumer that needs an exact minor asks for it (find_package(rotacal 0.1 EXACT)).
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rotacalConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rotacalConfig.cmake ${PROJECT_BINARY_DIR}/rotacalConfigVersion.cmake
  DESTINATION ${rotacal_cmake_dir} COMPONENT development)

# Debian packages (cpack -G DEB). The tool's Depends come from dpkg-shlibdeps on the binary (the
# shared libraries it really loads: libc, libstdc++, libgcc, libfmt, libsqlite3); the -dev
# package's are the packages whose CMake configs rotacalConfig.cmake finds.
set(CPACK_PACKAGE_NAME rotacal)
set(CPACK_PACKAGE_VENDOR "rotacal")
# The address the commits of this repository carry; replace it when the project has a public one.
set(CPACK_PACKAGE_CONTACT "rotacal dev <dev@rotacal>")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${CPACK_PACKAGE_CONTACT}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)  # the executable (install strips executables only: the static libraries keep their symbols)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime development)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # <name>_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME rotacal)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
# Per package: a synopsis line, then the extended description (CPack indents it; no package-wide
# CPACK_PACKAGE_DESCRIPTION_SUMMARY, which CPack would put before each synopsis).
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION
  "calibrate the rotary axes of five-axis machine tools with a touch probe
rotacal plans a probing cycle, writes it as an NC program for the controller (LinuxCNC, Fanuc,
Haas, Siemens, Heidenhain, Okuma), reads back what the controller recorded, identifies the
ISO 230-7 location errors of the rotary axes with their uncertainty, and writes the
compensation: offsets in the controller's own form, or the NC program rewritten.")
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_NAME rotacal-dev)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_DEPENDS
  "libeigen3-dev (>= 3.3), libfmt-dev, nlohmann-json3-dev (>= 3.10), libboost-dev (>= 1.74)")
set(CPACK_DEBIAN_DEVELOPMENT_DESCRIPTION
  "compensation library of rotacal for CAM post-processors
Static libraries, headers and CMake package of rotacal: find_package(rotacal) gives
rotacal::core (kinematics, location errors, per-pose compensation, REPORT.json reading) and
rotacal::postproc (errors of a REPORT.json, NC program rewriting).")
include(CPack)
