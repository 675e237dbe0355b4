#include "strategies/registry.hpp"

#include "strategies/narrowphase/entry_list.hpp"
#include "strategies/narrowphase/registry.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"
#include "strategies/plugin/plugin_strategy.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <stdexcept>

namespace ccd::strategies {

// One declaration per file of the build's list (strategy_files.inc, generated from CMakeLists.txt).
#define CCD_STRATEGY_FILE(file) std::vector<StrategyEntry> file##_entries();
#include "ccd/strategy_files.inc"
#undef CCD_STRATEGY_FILE

const std::vector<StrategyEntry>& strategy_entries() {
  static const std::vector<StrategyEntry> entries = narrowphase::gather_entries<StrategyEntry>({
#define CCD_STRATEGY_FILE(file) file##_entries,
#include "ccd/strategy_files.inc"
#undef CCD_STRATEGY_FILE
  });
  return entries;
}

const StrategyEntry& find_strategy(const std::string& name) {
  // Code from outside enters beside the built-ins: its entry is made at the first lookup (plugin_strategy.hpp).
  if (plugin::names_plugin(name)) return narrowphase::entry_made_once<StrategyEntry>(name, plugin::whole_step_entry);
  if (name.rfind(std::string(narrowphase::kAnswersHead) + ":", 0) == 0) {
    return narrowphase::entry_made_once<StrategyEntry>(name, plugin::answers_entry);
  }
  return narrowphase::entry_named(strategy_entries(), name, "strategy");
}

namespace {

/// A strategy whose narrow phase has provenance of its own (a plugin: its code and where it ran), or may not be called
/// from several threads at once (a plugin without CCDBENCH_THREAD_SAFE): the latter runs on one thread, the calling
/// one, in an arena of one (TBB then starts no worker in it). Its records say both (provenance).
class WithNarrowPhaseNotes final : public Strategy {
 public:
  WithNarrowPhaseNotes(std::unique_ptr<Strategy> inner, std::vector<std::pair<std::string, std::string>> notes, std::string one_thread_why)
      : inner_(std::move(inner)), notes_(std::move(notes)), why_(std::move(one_thread_why)) {
    if (!why_.empty()) arena_.emplace(1);
  }
  std::string name() const override { return inner_->name(); }
  void check_scene(const Scene& scene) const override { inner_->check_scene(scene); }
  void name_scene(const std::string& label) override { inner_->name_scene(label); }
  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    on_its_threads([&] { inner_->init(scene, first_frame); });
  }
  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    on_its_threads([&] { result = inner_->step(step, audit); });
    return result;
  }
  std::vector<std::pair<std::string, std::string>> provenance() const override {
    auto values = inner_->provenance();
    values.insert(values.end(), notes_.begin(), notes_.end());
    if (!why_.empty()) values.emplace_back("threads", "1: " + why_);
    return values;
  }

 private:
  std::unique_ptr<Strategy> inner_;
  template <class F>
  void on_its_threads(F&& f) {
    if (arena_) {
      arena_->execute(f);
    } else {
      f();
    }
  }

  std::vector<std::pair<std::string, std::string>> notes_;
  std::string why_;
  std::optional<tbb::task_arena> arena_;
};

}  // namespace

StrategySpec parse_strategy_spec(const std::string& spec) {
  StrategySpec parsed;
  auto [head, parameters] = narrowphase::split_spec(spec);
  // The '+' that joins strategy and narrow phase comes before any path (a path may hold a '+').
  const std::size_t plus = head.substr(0, head.find(':')).find('+');
  parsed.name = head.substr(0, plus);
  if (plus != std::string::npos) {
    parsed.narrow_phase = head.substr(plus + 1);
    if (parsed.narrow_phase.empty()) throw std::invalid_argument("malformed strategy spec '" + spec + "'");
  }
  if (parsed.name.empty()) throw std::invalid_argument("malformed strategy spec '" + spec + "'");
  parsed.parameters = std::move(parameters);
  return parsed;
}

StrategySpec strategy_names_of(const std::string& spec) {
  std::string head = spec.substr(0, spec.find(':'));
  const std::size_t plus = head.find('+');  // before the first ':', so never inside a path
  // plugin:PATH and answers:DIR keep their path (split_spec's rule), before or after the '+'.
  if (narrowphase::is_file_head(head.substr(plus == std::string::npos ? 0 : plus + 1)) && head.size() < spec.size()) {
    const std::size_t end = spec.find(':', head.size() + 1);
    head = spec.substr(0, end);
  }
  return {head.substr(0, plus), plus == std::string::npos ? std::string() : head.substr(plus + 1), {}};
}

bool from_outside(const std::string& spec) {
  const StrategySpec names = strategy_names_of(spec);
  return narrowphase::is_file_head(names.name.substr(0, names.name.find(':'))) ||
         narrowphase::is_file_head(names.narrow_phase.substr(0, names.narrow_phase.find(':')));
}

bool runs_host_method(const std::string& spec) {
  const StrategySpec names = strategy_names_of(spec);
  auto host = [](const std::string& name) { return name.substr(0, name.find(':')) == narrowphase::kHostMethodHead; };
  return host(names.name) || host(names.narrow_phase);
}

std::string short_label(const std::string& spec) {
  const StrategySpec names = strategy_names_of(spec);
  auto shorten = [](const std::string& name) {
    const std::size_t colon = name.find(':');
    if (colon == std::string::npos || !narrowphase::is_file_head(name.substr(0, colon))) return name;
    return name.substr(0, colon + 1) + std::filesystem::path(name.substr(colon + 1)).filename().string();
  };
  return shorten(names.name) + (names.narrow_phase.empty() ? "" : "+" + shorten(names.narrow_phase));
}

const StrategyEntry& strategy_entry_of(const std::string& spec) { return find_strategy(strategy_names_of(spec).name); }

std::unique_ptr<Strategy> make_strategy(const std::string& spec) {
  const StrategySpec parsed = parse_strategy_spec(spec);
  const StrategyEntry& entry = find_strategy(parsed.name);
  if (!entry.unavailable.empty()) throw std::invalid_argument(entry.name + " is not available: " + entry.unavailable);
  auto owns = [](const std::vector<narrowphase::KeySpec>& keys, const std::string& key) {
    return std::any_of(keys.begin(), keys.end(), [&](const narrowphase::KeySpec& k) { return k.name == key; });
  };
  if (!entry.takes_narrow_phase) {
    if (!parsed.narrow_phase.empty()) {
      throw std::invalid_argument(entry.name + " uses elementary tests of its own and takes no narrow phase ('" + spec + "')");
    }
    return entry.make({narrowphase::SpecReader(entry.name, entry.keys, parsed.parameters), nullptr});
  }
  const narrowphase::NarrowPhaseEntry& narrow =
      narrowphase::find_narrow_phase(parsed.narrow_phase.empty() ? narrowphase::kDefaultNarrowPhase : parsed.narrow_phase);
  // Each key to its owner; one that neither has is refused naming both lists (so `apccd:foo=1` is not blamed on
  // the narrow phase alone).
  narrowphase::SpecParameters own, narrow_keys;
  for (const auto& [key, value] : parsed.parameters) {
    if (owns(entry.keys, key)) {
      own[key] = value;
    } else if (owns(narrow.keys, key)) {
      narrow_keys[key] = value;
    } else {
      throw std::invalid_argument(entry.name + "+" + narrow.name + " has no parameter '" + key + "' (" + entry.name +
                                  "'s: " + narrowphase::key_names(entry.keys) + "; narrow phase " + narrow.name +
                                  "'s: " + narrowphase::key_names(narrow.keys) + ")");
    }
  }
  const narrowphase::SpecReader keys(entry.name, entry.keys, own);
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase = narrow.make(narrowphase::SpecReader(narrow.name, narrow.keys, narrow_keys));
  std::vector<std::pair<std::string, std::string>> notes = narrow_phase->provenance();
  const std::string why = narrow_phase->thread_safe() ? "" : "narrow phase " + narrow.name + " may not be called from several threads at once";
  if (!notes.empty() || !why.empty())
    return std::make_unique<WithNarrowPhaseNotes>(entry.make({keys, std::move(narrow_phase)}), std::move(notes), why);
  return entry.make({keys, std::move(narrow_phase)});
}

}  // namespace ccd::strategies
