# `cmake --install BUILD --prefix PREFIX` puts ccdbench where a plugin project finds it (README "Audit your CCD"):
#   PREFIX/bin/ccdbench
#   PREFIX/include/ccdbench/ccdbench_plugin.h, ccdbench_plugin.hpp
#   PREFIX/lib/cmake/ccdbench/ccdbenchConfig.cmake (+ version and targets): find_package(ccdbench) gives
#     ccdbench::plugin (the headers; a plugin links nothing else) and ccdbench::ccdbench (the program).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS ccdbench EXPORT ccdbenchTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS ccdbench_plugin_header EXPORT ccdbenchTargets)
install(FILES ${PROJECT_SOURCE_DIR}/strategies/plugin/ccdbench_plugin.h ${PROJECT_SOURCE_DIR}/strategies/plugin/ccdbench_plugin.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ccdbench)
install(EXPORT ccdbenchTargets NAMESPACE ccdbench:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ccdbenchConfig.cmake.in ${PROJECT_BINARY_DIR}/ccdbenchConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
# The plugin ABI has its own version (CCDBENCH_PLUGIN_ABI_VERSION); the package's says which ccdbench it is.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ccdbenchConfigVersion.cmake COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ccdbenchConfig.cmake ${PROJECT_BINARY_DIR}/ccdbenchConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
