// Loggers that belong to the plugin. ipc-toolkit's and Tight-Inclusion's default loggers register themselves by name
// in spdlog's registry, which is process-wide where spdlog is a shared library (Debian's): a second plugin of either
// in one process (in-process runs, a test that loads them all) would find the name taken and fail to create. Each is
// given a logger of its own instead, on stderr and in no registry.
#ifndef CCDBENCH_FIELD_PRIVATE_LOGGERS_HPP
#define CCDBENCH_FIELD_PRIVATE_LOGGERS_HPP

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <ipc/utils/logger.hpp>
#include <tight_inclusion/logger.hpp>

#include <memory>

namespace field {

/// ipc-toolkit's logger, printing errors only, and Tight-Inclusion's, at its own default level, both unregistered.
inline void use_private_loggers() {
  auto sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
  auto ipc_logger = std::make_shared<spdlog::logger>("ipctk", sink);
  ipc_logger->set_level(spdlog::level::err);
  ipc::set_logger(ipc_logger);
  ticcd::set_logger(std::make_shared<spdlog::logger>("ticcd", sink));
}

}  // namespace field

#endif  // CCDBENCH_FIELD_PRIVATE_LOGGERS_HPP
