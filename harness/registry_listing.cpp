#include "harness/registry_listing.hpp"

#include "harness/table.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/library.hpp"
#include "strategies/registry.hpp"

#include <ostream>

namespace ccd::harness {
namespace {

using nlohmann::json;

const char* kind_name(narrowphase::KeySpec::Kind kind) {
  switch (kind) {
    case narrowphase::KeySpec::Kind::number: return "number";
    case narrowphase::KeySpec::Kind::integer: return "integer";
    case narrowphase::KeySpec::Kind::choice: return "choice";
    case narrowphase::KeySpec::Kind::text: return "text";
  }
  return "text";
}

json keys_json(const std::vector<narrowphase::KeySpec>& keys) {
  json list = json::array();
  for (const narrowphase::KeySpec& key : keys) {
    json entry = {{"name", key.name}, {"kind", kind_name(key.kind)}, {"allowed", key.allowed()}, {"default", key.default_value}, {"help", key.help}};
    if (key.kind == narrowphase::KeySpec::Kind::number || key.kind == narrowphase::KeySpec::Kind::integer) {
      entry["minimum"] = key.range.minimum;
      entry["maximum"] = key.range.maximum;
    }
    if (key.kind == narrowphase::KeySpec::Kind::choice) entry["choices"] = key.choices;
    list.push_back(entry);
  }
  return list;
}

json sweep_json(const std::vector<narrowphase::SweepAxis>& sweeps) {
  json list = json::array();
  for (const narrowphase::SweepAxis& axis : sweeps) list.push_back({{"key", axis.key}, {"values", axis.values}});
  return list;
}

void print_keys(const json& keys, std::ostream& out) {
  if (keys.empty()) {
    out << "  no keys\n";
    return;
  }
  Table table({{"  key"}, {"values"}, {"default"}, {"what it changes"}});
  for (const json& key : keys) {
    table.add_row({"  " + key["name"].get<std::string>(), key["allowed"].get<std::string>(),
                   key["default"].get<std::string>().empty() ? "-" : key["default"].get<std::string>(), key["help"].get<std::string>()});
  }
  table.print(out);
}

std::string joined(const json& list) {
  std::string text;
  for (const json& item : list) text += (text.empty() ? "" : ", ") + item.get<std::string>();
  return text;
}

}  // namespace

json registry_listing(const std::vector<std::string>& plugins) {
  json strategies = json::array();
  // A plugin enters as a strategy (its whole step) and as a narrow phase (its queries), where it has each.
  std::vector<const strategies::StrategyEntry*> strategy_list;
  std::vector<const narrowphase::NarrowPhaseEntry*> narrow_list;
  for (const strategies::StrategyEntry& entry : strategies::strategy_entries()) strategy_list.push_back(&entry);
  for (const narrowphase::NarrowPhaseEntry& entry : narrowphase::narrow_phases()) narrow_list.push_back(&entry);
  for (const std::string& path : plugins) {
    const plugin::PluginDescription& description = plugin::plugin_description(path);
    const std::string name = std::string(narrowphase::kPluginHead) + ":" + path;
    if (description.answers_steps()) strategy_list.push_back(&strategies::find_strategy(name));
    if (description.answers_queries()) narrow_list.push_back(&narrowphase::find_narrow_phase(name));
  }
  for (const strategies::StrategyEntry* entry_pointer : strategy_list) {
    const strategies::StrategyEntry& entry = *entry_pointer;
    strategies.push_back({{"name", entry.name},
                          {"help", entry.help},
                          {"keys", keys_json(entry.keys)},
                          {"backends", entry.backends},
                          {"narrow_phase", entry.takes_narrow_phase ? "conservative (default) or NAME+NARROW" : "its own elementary tests"},
                          {"judged_by", entry.judging == strategies::Judging::triangle_pairs ? "triangle pairs" : "elementary pairs"},
                          {"baseline", entry.baseline},
                          {"available", entry.unavailable.empty()},
                          {"unavailable", entry.unavailable}});
  }
  json narrow_phases = json::array();
  for (const narrowphase::NarrowPhaseEntry* entry_pointer : narrow_list) {
    const narrowphase::NarrowPhaseEntry& entry = *entry_pointer;
    narrow_phases.push_back({{"name", entry.name},
                             {"help", entry.help},
                             {"keys", keys_json(entry.keys)},
                             {"backends", narrowphase::narrow_phase_backends(entry)},
                             {"conservative", entry.conservative},
                             {"sweep", sweep_json(entry.sweeps)}});
  }
  return {{"strategies", strategies}, {"narrow_phases", narrow_phases}};
}

int run_strategies(bool json_output, std::ostream& out, const std::vector<std::string>& plugins) {
  const json listing = registry_listing(plugins);
  if (json_output) {
    out << listing.dump(2) << '\n';
    return 0;
  }
  out << "Strategies: NAME[+NARROW][:key=value...], e.g. full+cubic64, apccd:nf_max=4:eta=1e-5 (a strategy's keys and its narrow\n"
         "phase's keys go after the name, in any order). The resolved spec, every default filled in, names the strategy in results.\n\n";
  for (const json& s : listing["strategies"]) {
    out << s["name"].get<std::string>() << ": " << s["help"].get<std::string>() << "\n  backends " << joined(s["backends"])
        << "; narrow phase: " << s["narrow_phase"].get<std::string>() << "; judged by " << s["judged_by"].get<std::string>() << "; speed-up against "
        << s["baseline"].get<std::string>() << "\n";
    if (!s["available"].get<bool>()) out << "  not available in this build: " << s["unavailable"].get<std::string>() << "\n";
    print_keys(s["keys"], out);
    out << "\n";
  }
  out << "Narrow phases (NARROW), also `queries --method` and `stress --method`:\n\n";
  for (const json& n : listing["narrow_phases"]) {
    out << n["name"].get<std::string>() << ": " << n["help"].get<std::string>() << "\n  backends " << joined(n["backends"]) << "; "
        << (n["conservative"].get<bool>() ? "conservative: judged on 0 misses and no late TOI" : "not conservative") << "\n";
    print_keys(n["keys"], out);
    out << "\n";
  }
  out << "Code from outside ccdbench (docs/audit.md): plugin:PATH[:key=value] names a plugin (its whole step as a\n"
         "strategy; NAME+plugin:PATH its queries as a narrow phase; --plugin PATH lists its keys above), answers:DIR a folder of\n"
         "per-step answer files (run --answers DIR), answers:FILE a file of per-query answers (queries --answers FILE).\n\n";
  out << "--json prints the same for scripts.\n";
  return 0;
}

}  // namespace ccd::harness
