# Run at every build (cmake -P): writes OUTPUT with a SHA-256 over the sources the exact reference's answers depend
# on (reference/, core/, and the truth cache's own format in harness/truth_cache.*), file names included. Cached
# truth is keyed by it, so any edit there makes old truth unreadable without anyone remembering to bump a version.
# configure_file rewrites OUTPUT only when the digest changes, so an unchanged tree recompiles nothing.
file(GLOB_RECURSE sources RELATIVE "${SOURCE_DIR}"
     "${SOURCE_DIR}/reference/*.cpp" "${SOURCE_DIR}/reference/*.hpp" "${SOURCE_DIR}/reference/CMakeLists.txt"
     "${SOURCE_DIR}/core/*.cpp" "${SOURCE_DIR}/core/*.hpp" "${SOURCE_DIR}/core/CMakeLists.txt"
     "${SOURCE_DIR}/harness/truth_cache.cpp" "${SOURCE_DIR}/harness/truth_cache.hpp")
list(SORT sources)
set(listing "")
foreach(source IN LISTS sources)
  file(SHA256 "${SOURCE_DIR}/${source}" digest)
  string(APPEND listing "${source} ${digest}\n")
endforeach()
string(SHA256 CCDBENCH_REFERENCE_SOURCE_DIGEST "${listing}")
list(LENGTH sources CCDBENCH_REFERENCE_SOURCE_FILES)
configure_file("${SOURCE_DIR}/cmake/source_digest.hpp.in" "${OUTPUT}" @ONLY)
