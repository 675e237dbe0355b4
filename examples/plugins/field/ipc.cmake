# ipc-toolkit's two CCD classes, TightInclusionCCD and AdditiveCCD, compiled from its sources with what they use (the
# distance functions and the logger) and nothing else: the whole toolkit's CMake downloads a dozen packages that
# Debian 12 does not have (libigl, scalable-ccd, simple-bvh, TinyAD, ...), none of which these classes use. The
# Tight-Inclusion they call is the one ipc-toolkit pins (TIGHT_INCLUSION_DIR), built by its own CMake with Debian's
# Eigen and spdlog.
if(NOT EXISTS "${TIGHT_INCLUSION_DIR}/src/tight_inclusion/ccd.hpp")
  message(FATAL_ERROR "TIGHT_INCLUSION_DIR=${TIGHT_INCLUSION_DIR}: not Tight-Inclusion's sources (no src/tight_inclusion/ccd.hpp)")
endif()
find_package(spdlog REQUIRED)
# Debian's spdlog uses the system's fmt and lacks spdlog/fmt/bundled/ranges.h, which both libraries' loggers include:
# one forwarding header stands in for it (as in examples/plugins/tight_inclusion/).
file(WRITE "${CMAKE_BINARY_DIR}/shim/spdlog/fmt/bundled/ranges.h" "#pragma once\n#include <fmt/ranges.h>\n")
add_subdirectory("${TIGHT_INCLUSION_DIR}" tight_inclusion EXCLUDE_FROM_ALL)
target_include_directories(tight_inclusion PUBLIC "${CMAKE_BINARY_DIR}/shim")

set(ipc_sources ccd/tight_inclusion_ccd.cpp ccd/additive_ccd.cpp distance/distance_type.cpp distance/edge_edge.cpp distance/line_line.cpp
                distance/point_edge.cpp distance/point_line.cpp distance/point_plane.cpp distance/point_point.cpp distance/point_triangle.cpp
                utils/logger.cpp)
list(TRANSFORM ipc_sources PREPEND "${FIELD_LIBRARY_DIR}/src/ipc/")
add_library(ipc_toolkit_ccd STATIC ${ipc_sources})
target_include_directories(ipc_toolkit_ccd PUBLIC "${FIELD_LIBRARY_DIR}/src" "${CMAKE_BINARY_DIR}/shim")
target_link_libraries(ipc_toolkit_ccd PUBLIC Eigen3::Eigen spdlog::spdlog tight_inclusion::tight_inclusion)
set_target_properties(ipc_toolkit_ccd PROPERTIES CXX_STANDARD 17)
field_plugin(ipc_tight_inclusion 17 ipc_toolkit_ccd)
field_plugin(ipc_additive 17 ipc_toolkit_ccd)
