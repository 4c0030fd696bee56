# Install, export and package (a library for CAM posts: docs/library.md).
#
#   cmake --install build --prefix PREFIX   bin/rotacal; lib/<multiarch>/librotacal.so.<version> with its
#                                           SONAME link librotacal.so.<major> and the link
#                                           librotacal.so; the public headers include/rotacal/*.hpp;
#                                           lib/<multiarch>/cmake/rotacal/rotacalConfig.cmake: in a consumer,
#                                           find_package(rotacal 0.1) gives rotacal::rotacal.
#   cpack -G DEB (in the build dir)         rotacal_<version>_<arch>.deb: the command-line tool;
#                                           librotacal0_<version>_<arch>.deb: the shared library;
#                                           rotacal-dev_<version>_<arch>.deb: headers, the
#                                           librotacal.so link, CMake package.
# Three install components, as Debian packages a library (policy 8.1, 8.4): `runtime` (the
# executable, which links the internal libraries statically and so needs no librotacal0),
# `library` (what a post loads at run time, in a package named after the SONAME, so that two
# ABIs could be installed side by side) and `development` (what a post is built with).
# scripts/package-check.sh proves all three, and runs lintian on them.
# The internal libraries (core, gcode, controllers, postproc, ...) and their headers are not
# installed: their types (Eigen, nlohmann::json) are no interface to promise.
include(CMakePackageConfigHelpers)

install(TARGETS rotacal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
# With the tool: its manual pages (rotacal.1.gz, rotacal-<command>.1.gz: help2man from its --help
# at build time, target rotacal_man, cli/CMakeLists.txt), its bash completion, its documents
# (README, licence, changelog) and the example machines a shop starts from.
if(TARGET rotacal_man)
  install(DIRECTORY ${PROJECT_BINARY_DIR}/cli/man/ DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime
    FILES_MATCHING PATTERN "*.1.gz")
endif()
install(FILES ${PROJECT_SOURCE_DIR}/cli/completion/rotacal.bash RENAME rotacal
  DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/bash-completion/completions COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CHANGELOG.md
  DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/rotacal COMPONENT runtime)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/machines DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/rotacal/examples
  COMPONENT runtime FILES_MATCHING PATTERN "*.json")
# The README's links lead into docs/ (the operator guides first), so docs/ travels beside it.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/rotacal
  COMPONENT runtime FILES_MATCHING PATTERN "*.md" PATTERN "*.png")
# Debian policy 8.1: a shared library is not executable (644).
install(TARGETS rotacal_shared EXPORT rotacalTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT library NAMELINK_COMPONENT development
  PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/rotacal/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rotacal
  COMPONENT development FILES_MATCHING PATTERN "*.hpp")
install(FILES ${PROJECT_BINARY_DIR}/include/rotacal/version.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rotacal
  COMPONENT development)

set(rotacal_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/rotacal)
install(EXPORT rotacalTargets NAMESPACE rotacal:: DESTINATION ${rotacal_cmake_dir} COMPONENT development)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rotacalConfig.cmake.in
  ${PROJECT_BINARY_DIR}/rotacalConfig.cmake INSTALL_DESTINATION ${rotacal_cmake_dir})
# The compatibility rule (docs/library.md): SOVERSION is the major; while the major is 0 the minor
# is the ABI, so find_package(rotacal 0.1) accepts 0.1.z only (SameMajorVersion would take any 0.y).
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(rotacal_compatibility SameMinorVersion)
else()
  set(rotacal_compatibility SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rotacalConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${rotacal_compatibility})
install(FILES ${PROJECT_BINARY_DIR}/rotacalConfig.cmake ${PROJECT_BINARY_DIR}/rotacalConfigVersion.cmake
  DESTINATION ${rotacal_cmake_dir} COMPONENT development)

# Debian packages (cpack -G DEB). The tool's and the library's Depends come from dpkg-shlibdeps on
# their binaries (the shared libraries they really load: libc, libstdc++, libgcc, libfmt, and
# libsqlite3 for the tool); the -dev package depends on the library of its exact version.
set(CPACK_PACKAGE_NAME rotacal)
set(CPACK_PACKAGE_VENDOR "rotacal")
# The address the commits of this repository carry; replace it when the project has a public one.
set(CPACK_PACKAGE_CONTACT "rotacal dev <dev@rotacal>")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${CPACK_PACKAGE_CONTACT}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)  # the executable and the shared library: their symbols are no use to a user
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime library development)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # <name>_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME rotacal)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
# Per package: a synopsis line, then the extended description (CPack indents it; no package-wide
# CPACK_PACKAGE_DESCRIPTION_SUMMARY, which CPack would put before each synopsis).
# Extended lines within 79 characters (CPack indents them by one; lintian reads 80 as too long).
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION
  "calibrate the rotary axes of five-axis machine tools with a touch probe
rotacal plans a probing cycle, writes it as an NC program for the controller
(LinuxCNC, Fanuc, Haas, Siemens, Heidenhain, Okuma), reads back what the
controller recorded, identifies the ISO 230-7 location errors of the rotary
axes with their uncertainty, and writes the compensation: offsets in the
controller's own form, or the NC program rewritten.")
set(rotacal_library_package librotacal${PROJECT_VERSION_MAJOR})
set(CPACK_DEBIAN_LIBRARY_PACKAGE_NAME ${rotacal_library_package})
set(CPACK_DEBIAN_LIBRARY_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_LIBRARY_PACKAGE_SHLIBDEPS ON)
# The shlibs file, through which dpkg-shlibdeps gives a post's package its Depends on the
# library: written here rather than by CPack (CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS), whose one
# relation cannot say the compatibility rule: this version up to the next minor while the major
# is 0 (the SONAME does not change with the minor), else up to the next major.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  math(EXPR rotacal_next_minor "${PROJECT_VERSION_MINOR} + 1")
  set(rotacal_abi_end 0.${rotacal_next_minor})
else()
  math(EXPR rotacal_abi_end "${PROJECT_VERSION_MAJOR} + 1")
endif()
file(WRITE ${PROJECT_BINARY_DIR}/debian-control/shlibs
  "librotacal ${PROJECT_VERSION_MAJOR} ${rotacal_library_package} (>= ${PROJECT_VERSION}), ${rotacal_library_package} (<< ${rotacal_abi_end}~)\n")
# The ldconfig trigger Debian's packages use (lintian: lacks-ldconfig-trigger). CPack also
# writes a postinst and postrm that call ldconfig; the trigger makes that call redundant, not
# wrong (lintian's warning maintscript-calls-ldconfig).
set(CPACK_DEBIAN_LIBRARY_PACKAGE_CONTROL_EXTRA ${PROJECT_SOURCE_DIR}/cmake/debian/triggers ${PROJECT_BINARY_DIR}/debian-control/shlibs)
set(CPACK_DEBIAN_LIBRARY_DESCRIPTION
  "compensation library of rotacal for CAM post-processors
The shared library of rotacal that a CAM post-processor loads: NC programs
compensated for the location errors of the rotary axes that rotacal
identified (as `rotacal compensate` writes them), single poses compensated,
and the program verifier of `rotacal check`.")
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_NAME rotacal-dev)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEVELOPMENT_PACKAGE_DEPENDS "${rotacal_library_package} (= ${PROJECT_VERSION})")
set(CPACK_DEBIAN_DEVELOPMENT_DESCRIPTION
  "compensation library of rotacal for CAM post-processors (development files)
Headers and CMake package of librotacal: find_package(rotacal) gives
rotacal::rotacal, a C++17 interface of standard-library types only
(rotacal/rotacal.hpp): NC programs compensated for a REPORT.json, single
poses compensated, programs verified.")
# Every package carries its copyright and changelog (Debian policy 12.5, 12.7).
string(TIMESTAMP rotacal_changelog_date "%a, %d %b %Y %H:%M:%S +0000" UTC)  # SOURCE_DATE_EPOCH when set
foreach(component runtime library development)
  string(TOUPPER ${component} c)
  set(pkg ${CPACK_DEBIAN_${c}_PACKAGE_NAME})
  set(doc ${PROJECT_BINARY_DIR}/debian-doc/${pkg})
  configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/copyright ${doc}/copyright COPYONLY)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/changelog.in ${doc}/changelog @ONLY)
  # gzip -9n (no name or time in its header), at configure time: cpack builds no target first.
  execute_process(COMMAND gzip -9nc ${doc}/changelog OUTPUT_FILE ${doc}/changelog.gz COMMAND_ERROR_IS_FATAL ANY)
  # A native package's changelog is changelog.gz (Debian policy 12.7: the version has no revision).
  install(FILES ${doc}/copyright ${doc}/changelog.gz DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/${pkg}
    COMPONENT ${component})
endforeach()
include(CPack)
