# Every dependency is a Debian 12 package; scripts/setup.sh installs them.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(CGAL 5.5 REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(PkgConfig REQUIRED)
# Prefixed: CGAL's own FindGMP/FindMPFR read the unprefixed GMP_* and MPFR_* variables.
pkg_check_modules(CCD_GMP REQUIRED IMPORTED_TARGET gmp gmpxx)
pkg_check_modules(CCD_MPFR REQUIRED IMPORTED_TARGET mpfr)
# Content digests of cache keys, resumed cells and checksums (datasets/content_hash.hpp).
pkg_check_modules(CCD_XXHASH REQUIRED IMPORTED_TARGET libxxhash)
# libccd (GJK): the strategies cull cloth faces against analytic shapes with it (strategies/face_shape.hpp).
pkg_check_modules(CCD REQUIRED IMPORTED_TARGET ccd)

# Optional backends: ON by default when the distribution's package is found, and said clearly when OFF.
# ccd_optional_feature(NAME FOUND DESCRIPTION PACKAGES): the option CCDBENCH_WITH_NAME defaults to FOUND (a value
# given with -D is kept, as option() keeps a cache entry); ON without the package is an error naming PACKAGES.
function(ccd_optional_feature name found description packages)
  option(CCDBENCH_WITH_${name} "${description}" ${found})
  if(CCDBENCH_WITH_${name} AND NOT found)
    message(FATAL_ERROR "CCDBENCH_WITH_${name}=ON but it was not found: install ${packages} (scripts/setup.sh does), "
                        "or configure with -DCCDBENCH_WITH_${name}=OFF")
  endif()
endfunction()

find_package(OpenCL QUIET)
ccd_optional_feature(OPENCL "${OpenCL_FOUND}" "Build the OpenCL backend (full:backend=opencl, ccdbench devices)"
                     "ocl-icd-opencl-dev opencl-headers pocl-opencl-icd")

find_package(fcl QUIET)
if(fcl_FOUND AND CCD_FOUND)
  set(_ccd_fcl_found ON)
else()
  set(_ccd_fcl_found OFF)
endif()
ccd_optional_feature(FCL "${_ccd_fcl_found}" "Build the FCL baseline strategies" "libfcl-dev libccd-dev (FCL and libccd)")

# MPI spreads run, truth and queries over ranks (harness/work_queue.hpp); without it the program is the same,
# single-process one.
find_package(MPI QUIET COMPONENTS CXX)
ccd_optional_feature(MPI "${MPI_CXX_FOUND}" "Spread run, truth and queries over MPI ranks (mpirun -n N ccdbench ...)"
                     "libopenmpi-dev openmpi-bin")

foreach(_feature OPENCL FCL MPI)
  if(CCDBENCH_WITH_${_feature})
    message(STATUS "ccdbench: CCDBENCH_WITH_${_feature} = ON")
  else()
    message(WARNING "ccdbench: CCDBENCH_WITH_${_feature} = OFF: not built (its strategies are reported as unavailable, and "
                    "`ccdbench --version` says so)")
  endif()
endforeach()
