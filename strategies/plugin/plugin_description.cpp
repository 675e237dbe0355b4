// A plugin's description, made once per process (isolation.hpp: plugin_description).
#include "ccd/config.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/library.hpp"
#include "strategies/plugin/loaded_code.hpp"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

namespace ccd::plugin {

namespace {

std::mutex& description_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

const PluginDescription& plugin_description(const std::string& given) {
  static std::map<std::string, std::unique_ptr<const PluginDescription>> described;
  const std::string key = std::filesystem::absolute(given).lexically_normal().string();
  {
    std::lock_guard lock(description_mutex());
    if (const auto it = described.find(key); it != described.end()) return *it->second;
  }
#if CCDBENCH_GUARD_DESCRIBE_IN_CHILD
  PluginDescription made = describe_in_child(given);
#if CCDBENCH_GUARD_IDENTITY
  // Its identity is this process's to find, from its files, never the child's to say: the code the child ran could
  // have written any description.
  made.objects = plugin_objects_on_disk(made.path);
  made.digest = combined_digest(made.objects);
#endif
  std::lock_guard lock(description_mutex());
#else
  // Without the guard: loaded into this process to be described (a crash at load ends the run).
  std::lock_guard lock(description_mutex());
  std::error_code error;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(std::filesystem::absolute(given), error);
  PluginDescription made = library_loaded_at((error ? std::filesystem::absolute(given) : canonical).string())->description();
#endif
  auto it = described.find(key);
  if (it == described.end()) it = described.emplace(key, std::make_unique<const PluginDescription>(std::move(made))).first;
  return *it->second;
}

}  // namespace ccd::plugin
