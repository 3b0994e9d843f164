# The installed package (docs/install.md): `cmake --install build --prefix P` (or the .deb of
# `cpack`) writes, relative to P,
#   bin/fivebar                                        the CLI                      (component cli)
#   share/fivebar/{scad,schemas,designs,docs}          its data, found relative to bin/ at run time
#   share/bash-completion/completions/fivebar, share/zsh/vendor-completions/_fivebar, share/man/man1/
#   share/doc/fivebar/{LICENSE,CITATION.cff,CHANGELOG.md,README.md}
#   include/fivebar/, lib/libfivebar*.a                the libraries                (component dev)
#   lib/cmake/fivebar/fivebarConfig.cmake (+ Version, Targets)  find_package(fivebar COMPONENTS ...)
#   lib/python3.X/dist-packages/fivebar/               the Python module            (component python)
# Every path is relative to the prefix: the tree can be moved (test/install/check_install.sh).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(FIVEBAR_INSTALL_SHAREDIR ${CMAKE_INSTALL_DATADIR}/fivebar)
set(FIVEBAR_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/fivebar)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/fivebarConfig.cmake.in
  ${PROJECT_BINARY_DIR}/fivebarConfig.cmake
  INSTALL_DESTINATION ${FIVEBAR_INSTALL_CMAKEDIR}
  PATH_VARS FIVEBAR_INSTALL_SHAREDIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fivebarConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fivebarConfig.cmake ${PROJECT_BINARY_DIR}/fivebarConfigVersion.cmake
        DESTINATION ${FIVEBAR_INSTALL_CMAKEDIR} COMPONENT dev)

if(FIVEBAR_CORE_ONLY)
  return()  # the core's library and headers only (lib/CMakeLists.txt)
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/scad/ DESTINATION ${FIVEBAR_INSTALL_SHAREDIR}/scad COMPONENT cli)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/schemas/ DESTINATION ${FIVEBAR_INSTALL_SHAREDIR}/schemas COMPONENT cli)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${FIVEBAR_INSTALL_SHAREDIR}/docs COMPONENT cli
        FILES_MATCHING PATTERN "*.md" PATTERN "schemas" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/designs/ DESTINATION ${FIVEBAR_INSTALL_SHAREDIR}/designs COMPONENT cli)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CITATION.cff ${PROJECT_SOURCE_DIR}/CHANGELOG.md
              ${PROJECT_SOURCE_DIR}/README.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT cli)

# A Debian package of everything above: `cpack -G DEB --config build/CPackConfig.cmake`.
set(CPACK_PACKAGE_NAME fivebar)
set(CPACK_PACKAGE_VENDOR "the fivebar authors")
set(CPACK_PACKAGE_CONTACT "the fivebar authors")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Design five-bar-linkage cutaneous haptic devices (IROS 2022)")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# The shared libraries the binaries link (dpkg-shlibdeps), plus the tools `parts` runs.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "openscad")
include(CPack)
