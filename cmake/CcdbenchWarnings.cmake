# Warnings are an interface target linked PRIVATE, so they apply to our code and never leak to users of a target.
add_library(ccd_warnings INTERFACE)
add_library(ccd::warnings ALIAS ccd_warnings)
target_compile_options(ccd_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  -Wconversion -Wno-sign-conversion -Wimplicit-fallthrough -Wdouble-promotion -Wformat=2)

# Helper: one library target per source folder, named ccd::<folder>.
function(ccd_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(ccd_${name} ${ARG_SOURCES})
  add_library(ccd::${name} ALIAS ccd_${name})
  target_include_directories(ccd_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(ccd_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ccd::warnings ${ARG_PRIVATE_DEPS})
endfunction()
