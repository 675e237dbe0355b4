# Fails when a folder includes a header it must not see (docs/DESIGN.md §2):
#   core/ sees only core/; datasets/ sees core/ and datasets/;
#   reference/ never includes strategies/, and strategies/ never includes reference/.
set(rules
  "core:datasets/|reference/|strategies/|harness/"
  "datasets:reference/|strategies/|harness/"
  "reference:strategies/|harness/"
  "strategies:reference/|harness/")
set(violations "")
foreach(rule IN LISTS rules)
  string(REPLACE ":" ";" parts "${rule}")
  list(GET parts 0 folder)
  list(GET parts 1 forbidden)
  file(GLOB_RECURSE sources "${SOURCE_DIR}/${folder}/*.hpp" "${SOURCE_DIR}/${folder}/*.cpp" "${SOURCE_DIR}/${folder}/*.cl")
  foreach(source IN LISTS sources)
    file(STRINGS "${source}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"(${forbidden})")
    foreach(line IN LISTS lines)
      string(APPEND violations "  ${source}: ${line}\n")
    endforeach()
  endforeach()
endforeach()
if(violations)
  message(FATAL_ERROR "layering violations:\n${violations}")
endif()
message(STATUS "layering: include rules hold")
