# `cmake --install` and the .deb (issue 17; docs/INSTALL.md): crunchhost, the tools, the udev
# rule, the shipped models, the public headers and the CMake package (find_package(Crunch) gives
# Crunch::crunch). Install rules add nothing to the build itself: they run only at
# `cmake --install` / `cpack`.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CRUNCH_AREAS core robot scene signal io behaviour blackboard mapping exploration render session
                 serve)
set(crunch_area_targets "")
foreach(area ${CRUNCH_AREAS})
  list(APPEND crunch_area_targets crunch_${area})
endforeach()
# crunch_warnings is an INTERFACE library the areas link PRIVATE: a static library's private
# links are part of its exported link interface ($<LINK_ONLY:...>), so it must be exported too
# (it carries no compile options to a consumer through LINK_ONLY).
install(TARGETS crunch ${crunch_area_targets} whisker_core crunch_warnings
        EXPORT CrunchTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/host/include/crunch
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/firmware/core/include/whisker
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)
install(EXPORT CrunchTargets NAMESPACE Crunch::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Crunch COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/CrunchConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/CrunchConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Crunch)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/CrunchConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/CrunchConfig.cmake ${PROJECT_BINARY_DIR}/CrunchConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Crunch COMPONENT dev)

# The program, the board-flashing tool, the udev rule and the models crunchhost loads by default
# (signal::shippedModelsPath finds them beside an installed binary).
install(TARGETS crunchhost RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/tools/flash-whisker-board
        DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/tools/udev/99-crunchbot.rules
        DESTINATION lib/udev/rules.d COMPONENT runtime)
install(FILES ${PROJECT_SOURCE_DIR}/models/sim_models.json
        DESTINATION ${CMAKE_INSTALL_DATADIR}/crunchbot/models COMPONENT runtime)
# The man page host/app/CMakeLists.txt makes with help2man (target crunchhost_man, in ALL).
install(FILES ${PROJECT_BINARY_DIR}/crunchhost.1
        DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT runtime)

# `cpack -G DEB` in the build directory: crunchbot_<version>_<arch>.deb, one package with both
# components, installed under /usr (`apt install ./crunchbot_*.deb`). Its run-time dependencies
# come from dpkg-shlibdeps (libcairo2, libusb-1.0-0, libode8, libyaml-cpp0.7, ...); building
# against the CMake package needs the -dev packages it Recommends.
set(CPACK_PACKAGE_NAME crunchbot)
set(CPACK_PACKAGE_VENDOR "CrunchBot")
set(CPACK_PACKAGE_CONTACT "CrunchBot maintainers <crunchbot@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Whisker mapping for an iRobot Create: crunchhost, the crunch library and its CMake package")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_GENERATOR DEB)
set(CPACK_DEB_COMPONENT_INSTALL OFF)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "libeigen3-dev, nlohmann-json3-dev, libyaml-cpp-dev, libcairo2-dev, libusb-1.0-0-dev, libcpp-httplib-dev, pkg-config, cmake")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
