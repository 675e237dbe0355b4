# `cmake --install BUILD --prefix PREFIX` puts ccdbench where a plugin project finds it (docs/audit.md):
#   PREFIX/bin/ccdbench
#   PREFIX/include/ccdbench/ccdbench_plugin.h, ccdbench_plugin.hpp (the plugin ABI), ccdbench.hpp (the C++ API)
#   PREFIX/lib/libccdbench.so (the C++ API)
#   PREFIX/lib/cmake/ccdbench/ccdbenchConfig.cmake (+ version and targets): find_package(ccdbench) gives
#     ccdbench::plugin (the headers; a plugin links nothing else), ccdbench::library (the C++ API) and
#     ccdbench::ccdbench (the program).
#   PREFIX/share/ccdbench/plugin-template/ (examples/plugin/: the template a plugin project starts from)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS ccdbench EXPORT ccdbenchTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/plugin/ DESTINATION ${CMAKE_INSTALL_DATADIR}/ccdbench/plugin-template)
install(TARGETS ccdbench_plugin_header EXPORT ccdbenchTargets)
set_target_properties(ccdbench_library PROPERTIES EXPORT_NAME library)
install(TARGETS ccdbench_library EXPORT ccdbenchTargets LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(FILES ${PROJECT_SOURCE_DIR}/api/ccdbench/ccdbench.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ccdbench)
install(FILES ${PROJECT_SOURCE_DIR}/strategies/plugin/ccdbench_plugin.h ${PROJECT_SOURCE_DIR}/strategies/plugin/ccdbench_plugin.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ccdbench)
install(EXPORT ccdbenchTargets NAMESPACE ccdbench:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ccdbenchConfig.cmake.in ${PROJECT_BINARY_DIR}/ccdbenchConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
# The plugin ABI has its own version (CCDBENCH_PLUGIN_ABI_VERSION); the package's says which ccdbench it is.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ccdbenchConfigVersion.cmake COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ccdbenchConfig.cmake ${PROJECT_BINARY_DIR}/ccdbenchConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/ccdbench)
