# scripts/field/build.sh on a machine without the libraries' sources (CI): it names each library whose sources are
# missing and exits with status 3, its documented status for that, without building anything (--sources-only).
# Usage: cmake -DSOURCE_DIR=... -DWORK_DIR=... -P tests/check_field_build.cmake
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/no-sources")
execute_process(COMMAND ${CMAKE_COMMAND} -E env CCDBENCH_FIELD_SOURCES=${WORK_DIR}/no-sources CCDBENCH_FIELD_WORK=${WORK_DIR}/work
                        bash "${SOURCE_DIR}/scripts/field/build.sh" --sources-only
                RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE errors)
if(NOT status EQUAL 3)
  message(FATAL_ERROR "field build: exit status ${status} without sources, not 3:\n${output}${errors}")
endif()
foreach(library IN ITEMS tight_inclusion ipc fprf msrf rp_bsc rrp tight_ccd interval exact_root_parity)
  if(NOT output MATCHES "${library} +MISSING: no copy of [^\n]+ \\(no git repository ${WORK_DIR}/no-sources/")
    message(FATAL_ERROR "field build: ${library} is not named as missing its sources:\n${output}${errors}")
  endif()
endforeach()
if(EXISTS "${WORK_DIR}/work")
  message(FATAL_ERROR "field build: --sources-only wrote ${WORK_DIR}/work")
endif()
message(STATUS "field build: every library named as missing its sources, exit status 3")
