#pragma once
/// @file
/// The OpenCL C source of every kernel, embedded at build time (cmake/embed_kernels.cmake) so that a carried
/// binary needs no file beside it: kernels/prelude.cl, self_test.cl, full.cl and apccd.cl, each with the narrow
/// phases' shared files it includes (strategies/narrowphase/shared/) expanded in place, the first time only; every
/// file's text is preceded by a #line directive so that build logs name the file.

namespace ccd::opencl {

const char* kernel_source();

}  // namespace ccd::opencl
