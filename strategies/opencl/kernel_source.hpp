#pragma once
/// @file
/// The OpenCL C source of every kernel, embedded at build time (cmake/embed_kernels.cmake) so that a carried
/// binary needs no file beside it: kernels/prelude.cl, the narrow phases' shared files
/// (strategies/narrowphase/shared/geometry.h, inclusion.h), then kernels/self_test.cl and kernels/full.cl, each
/// preceded by a #line directive so that build logs name the file.

namespace ccd::opencl {

const char* kernel_source();

}  // namespace ccd::opencl
