/* What the narrow phases' shared files (strategies/narrowphase/shared/) expect from their environment, in OpenCL C
 * 1.2: double precision, no contraction into fused multiply-adds (the host compiles with -ffp-contract=off), and
 * the dot-product order of the host's double code. */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

typedef double ccd_real;
typedef ulong ccd_ulong;
#define ccd_real_epsilon DBL_EPSILON
#define ccd_dot_sums_right 0

#ifndef CCD_GROUP_SIZE
#error "CCD_GROUP_SIZE (the work-group size of the counting kernels) must be defined by the host"
#endif

/* Sub-boxes a conservative query may hold on the device (private memory, 56 bytes each; the backend's sub_boxes
 * key). A query that needs more reports an overflow and is decided again with more room (shared/inclusion.h). */
#ifndef CCD_DEVICE_SUB_BOXES
#error "CCD_DEVICE_SUB_BOXES must be defined by the host (kernel_defines)"
#endif

/* The deep pass's build (-DCCD_DEEP_PASS; Context::kernel, Build::deep): the conservative search keeps its
 * sub-boxes in device memory (narrow_conservative_deep), so the kernels that keep them in a private array are left
 * out of it. */
#ifdef CCD_DEEP_PASS
#define CCD_SUB_BOX_SPACE global
#endif
