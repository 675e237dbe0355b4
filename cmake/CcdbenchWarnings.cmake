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

# Helper: a registry whose list is the build's (strategies/narrowphase_registry.hpp, strategies/registry.hpp).
# Compiles FILE.cpp for each FILE into `target` and writes generated/ccd/<list_name>.inc, one line
# `CCD_<LIST_NAME in capitals, without its final S>(BASENAME)` per file, which the registry includes to call each
# file's entries function; so adding an entry is one new file and one line in its folder's CMakeLists.txt.
function(ccd_add_registry target list_name)
  string(TOUPPER "${list_name}" macro)
  string(REGEX REPLACE "S$" "" macro "${macro}")
  set(lines "// Generated from ${CMAKE_CURRENT_LIST_FILE}: do not edit.\n")
  foreach(file IN LISTS ARGN)
    target_sources(${target} PRIVATE ${file}.cpp)
    get_filename_component(base ${file} NAME)
    string(APPEND lines "CCD_${macro}(${base})\n")
  endforeach()
  file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/generated/ccd/${list_name}.inc CONTENT "${lines}")
  set_property(GLOBAL PROPERTY ccd_registry_${list_name} ${ARGN})  # the list, for a test that adds an entry to it
  target_link_libraries(${target} PRIVATE ccd::config)
endfunction()
