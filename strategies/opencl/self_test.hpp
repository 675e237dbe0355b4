#pragma once
/// @file
/// The start-up check that a device computes what the host computes: a product-sum that an FMA would change,
/// subnormal doubles, correctly rounded sqrt and division, and both narrow phases on seeded pairs at scales from
/// 2^-900 to 2^900 compared bit for bit with the host's (kernels/self_test.cl).

#include "strategies/opencl/runtime.hpp"

namespace ccd::opencl {

/// The seed of the self-test's pairs (fixed, so every device is checked on the same cases; it is in the message).
inline constexpr unsigned kSelfTestSeed = 20261123;

/// @throws std::invalid_argument naming the first case where the device's result differs from the host's.
void check_device_arithmetic(Context& context);

/// The same for the deep pass's build (Context::Build::deep): its kernel on the self-test's pairs with `capacity`
/// sub-boxes each in device memory, each answer and TOI bit for bit the host's.
/// @throws std::invalid_argument as check_device_arithmetic.
void check_deep_pass_arithmetic(Context& context, std::size_t capacity);

}  // namespace ccd::opencl
