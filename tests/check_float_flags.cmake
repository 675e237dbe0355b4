# Fails when the build or the sources ask for floating-point semantics other than IEEE 754 round-to-nearest with
# subnormals: the conservative tests' error budgets (and the exact reference's filter) assume them. Checks the
# flags this build was configured with (FLAGS) and every build file and source of the project, for
# -ffast-math, -Ofast, -funsafe-math-optimizations, -ffinite-math-only, -fno-signed-zeros and flush-to-zero
# (-mdaz-ftz, _MM_SET_FLUSH_ZERO_MODE, _MM_SET_DENORMALS_ZERO_MODE), contraction into FMA (-ffp-contract=fast|on;
# the top-level CMakeLists.txt must turn it off), and the OpenCL build options that do the same.
set(forbidden "-ffp-contract=fast|-ffp-contract=on|-ffast-math|-Ofast|-funsafe-math-optimizations|-ffinite-math-only|-fno-signed-zeros|-mdaz-ftz|_MM_SET_FLUSH_ZERO_MODE|_MM_SET_DENORMALS_ZERO_MODE|-cl-fast-relaxed-math|-cl-unsafe-math-optimizations|-cl-finite-math-only|-cl-denorms-are-zero|-cl-mad-enable")
set(violations "")
if(FLAGS MATCHES "(${forbidden})")
  string(APPEND violations "  the build's flags: ${FLAGS}\n")
endif()
file(GLOB_RECURSE files "${SOURCE_DIR}/CMakeLists.txt" "${SOURCE_DIR}/*.cmake" "${SOURCE_DIR}/CMakePresets.json"
     "${SOURCE_DIR}/core/*" "${SOURCE_DIR}/datasets/*" "${SOURCE_DIR}/reference/*" "${SOURCE_DIR}/strategies/*"
     "${SOURCE_DIR}/harness/*" "${SOURCE_DIR}/benchmarks/*")
foreach(file IN LISTS files)
  # tests/plugins/ builds one plugin the way a user's fast-math build is made, to show that its load cannot change
  # ccdbench's arithmetic (docs/DESIGN.md §10): that test library is the one place the flags are meant.
  if(file MATCHES "/build/|check_float_flags.cmake$|/tests/plugins/CMakeLists.txt$")
    continue()
  endif()
  file(STRINGS "${file}" lines REGEX "(${forbidden})")
  foreach(line IN LISTS lines)
    string(APPEND violations "  ${file}: ${line}\n")
  endforeach()
endforeach()
# Contraction into FMA would change every narrow phase's bits where a target has FMA (the x86-64-v3 clones of the
# conservative search, OpenCL devices): the project turns it off for every target, and must keep doing so.
file(READ "${SOURCE_DIR}/CMakeLists.txt" top_level)
if(NOT top_level MATCHES "add_compile_options\\(-ffp-contract=off\\)")
  string(APPEND violations "  CMakeLists.txt: add_compile_options(-ffp-contract=off) is missing\n")
endif()
if(violations)
  message(FATAL_ERROR "floating-point semantics changed:\n${violations}")
endif()
message(STATUS "float flags: IEEE semantics kept")
