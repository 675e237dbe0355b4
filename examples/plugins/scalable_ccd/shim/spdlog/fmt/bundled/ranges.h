// Scalable CCD's logger.hpp includes spdlog's bundled fmt (spdlog/fmt/bundled/ranges.h); Debian's spdlog is built on
// the system's fmt (SPDLOG_FMT_EXTERNAL) and ships no bundled copy. This header stands in for it.
#pragma once
#include <fmt/ranges.h>
