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

# Optional backends: ON by default when the distribution's package is found, and said clearly when OFF.
find_package(OpenCL QUIET)
if(NOT DEFINED CCDBENCH_WITH_OPENCL)
  set(_ccd_opencl_default ${OpenCL_FOUND})
else()
  set(_ccd_opencl_default ${CCDBENCH_WITH_OPENCL})
endif()
option(CCDBENCH_WITH_OPENCL "Build the OpenCL backend of apccd" ${_ccd_opencl_default})
if(CCDBENCH_WITH_OPENCL AND NOT OpenCL_FOUND)
  message(FATAL_ERROR "CCDBENCH_WITH_OPENCL=ON but OpenCL was not found: install ocl-icd-opencl-dev opencl-headers "
                      "pocl-opencl-icd (scripts/setup.sh does), or configure with -DCCDBENCH_WITH_OPENCL=OFF")
endif()

find_package(fcl QUIET)
pkg_check_modules(CCD QUIET IMPORTED_TARGET ccd)
if(NOT DEFINED CCDBENCH_WITH_FCL)
  if(fcl_FOUND AND CCD_FOUND)
    set(_ccd_fcl_default ON)
  else()
    set(_ccd_fcl_default OFF)
  endif()
else()
  set(_ccd_fcl_default ${CCDBENCH_WITH_FCL})
endif()
option(CCDBENCH_WITH_FCL "Build the FCL baseline strategies" ${_ccd_fcl_default})
if(CCDBENCH_WITH_FCL AND NOT (fcl_FOUND AND CCD_FOUND))
  message(FATAL_ERROR "CCDBENCH_WITH_FCL=ON but FCL or libccd was not found: install libfcl-dev libccd-dev "
                      "(scripts/setup.sh does), or configure with -DCCDBENCH_WITH_FCL=OFF")
endif()

# MPI spreads run, truth and queries over ranks (harness/work_queue.hpp); without it the program is the same,
# single-process one.
find_package(MPI QUIET COMPONENTS CXX)
if(NOT DEFINED CCDBENCH_WITH_MPI)
  set(_ccd_mpi_default ${MPI_CXX_FOUND})
else()
  set(_ccd_mpi_default ${CCDBENCH_WITH_MPI})
endif()
option(CCDBENCH_WITH_MPI "Spread run, truth and queries over MPI ranks (mpirun -n N ccdbench ...)" ${_ccd_mpi_default})
if(CCDBENCH_WITH_MPI AND NOT MPI_CXX_FOUND)
  message(FATAL_ERROR "CCDBENCH_WITH_MPI=ON but MPI was not found: install libopenmpi-dev openmpi-bin "
                      "(scripts/setup.sh does), or configure with -DCCDBENCH_WITH_MPI=OFF")
endif()

foreach(_feature OPENCL FCL MPI)
  if(CCDBENCH_WITH_${_feature})
    message(STATUS "ccdbench: CCDBENCH_WITH_${_feature} = ON")
  else()
    message(WARNING "ccdbench: CCDBENCH_WITH_${_feature} = OFF: its strategies will be reported as unavailable")
  endif()
endforeach()
