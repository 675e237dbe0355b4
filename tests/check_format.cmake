# Fails when a source file is not laid out as .clang-format says (docs/STYLE.md "Build"): `clang-format --dry-run
# --Werror` over every C, C++ and OpenCL file of the project (tests/CMakeLists.txt runs it with clang-format 14,
# Debian 12's: layout depends on the version).
# Usage: cmake -DSOURCE_DIR=... -DCLANG_FORMAT=PATH -P check_format.cmake
set(patterns)
foreach(folder core datasets reference strategies harness tests benchmarks examples)
  list(APPEND patterns "${SOURCE_DIR}/${folder}/*.hpp" "${SOURCE_DIR}/${folder}/*.cpp" "${SOURCE_DIR}/${folder}/*.h"
       "${SOURCE_DIR}/${folder}/*.c" "${SOURCE_DIR}/${folder}/*.cl")
endforeach()
file(GLOB_RECURSE sources ${patterns})
list(LENGTH sources count)
if(count LESS 200)
  message(FATAL_ERROR "only ${count} source files found under ${SOURCE_DIR}: the scan is broken")
endif()
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror --style=file ${sources} RESULT_VARIABLE status ERROR_VARIABLE errors)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "files clang-format would change (run clang-format -i on them):\n${errors}")
endif()
message(STATUS "format: ${count} files as .clang-format says")
