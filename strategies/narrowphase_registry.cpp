#include "strategies/narrowphase_registry.hpp"

#include "strategies/narrowphase/entry_list.hpp"
#include "strategies/plugin/host_method.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

namespace ccd::narrowphase {

// One declaration per file of the build's list (narrow_phase_files.inc, generated from CMakeLists.txt).
#define CCD_NARROW_PHASE_FILE(file) std::vector<NarrowPhaseEntry> file##_entries();
#include "ccd/narrow_phase_files.inc"
#undef CCD_NARROW_PHASE_FILE

const std::vector<NarrowPhaseEntry>& narrow_phases() {
  static const std::vector<NarrowPhaseEntry> entries = gather_entries<NarrowPhaseEntry>({
#define CCD_NARROW_PHASE_FILE(file) file##_entries,
#include "ccd/narrow_phase_files.inc"
#undef CCD_NARROW_PHASE_FILE
  });
  return entries;
}

std::string narrow_phase_list() { return entry_names(narrow_phases()); }

bool is_narrow_phase(const std::string& name) {
  return plugin::names_plugin(name) || plugin::names_host_method(name) || find_entry(narrow_phases(), name) != nullptr;
}

const NarrowPhaseEntry& find_narrow_phase(const std::string& name) {
  // A plugin enters beside the built-ins: its entry is made from its library at the first lookup.
  if (plugin::names_plugin(name)) return entry_made_once<NarrowPhaseEntry>(name, plugin::narrow_phase_entry);
  // A method of the calling program (the C++ API's register_method), for as long as it is registered.
  if (plugin::names_host_method(name)) return plugin::host_method_entry(name);
  return entry_named(narrow_phases(), name, "narrow phase");
}

std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const SpecParameters& parameters) {
  const NarrowPhaseEntry& entry = find_narrow_phase(name);
  return entry.make(SpecReader(entry.name, entry.keys, parameters));
}

std::unique_ptr<NarrowPhase> make_narrow_phase_from_spec(const std::string& spec) {
  const auto [name, parameters] = split_spec(spec);
  return make_narrow_phase(name, parameters);
}

ResolvedNarrowPhase resolve_narrow_phase(const NarrowPhaseEntry& entry, const SpecReader& keys) {
  // Code from outside has no device form, and says its name without being loaded.
  if (entry.resolve) return {entry.resolve(keys), entry.conservative, false};
  const std::unique_ptr<NarrowPhase> made = entry.make(keys);
  return {made->name(), made->conservative(), made->device_form().has_value()};
}

std::vector<std::string> narrow_phase_backends(const NarrowPhaseEntry& entry) {
  std::vector<std::string> backends{"cpu"};
  if (entry.make(SpecReader(entry.name, entry.keys, {}))->device_form()) backends.push_back("opencl");
  return backends;
}

}  // namespace ccd::narrowphase
