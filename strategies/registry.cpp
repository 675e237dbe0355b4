#include "strategies/registry.hpp"

#include "strategies/narrowphase/entry_list.hpp"
#include "strategies/narrowphase_registry.hpp"
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
  void prepare() override {
    on_its_threads([&] { inner_->prepare(); });
  }
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

StrategySpec parse_strategy_spec(const std::string& text) {
  auto [head, parameters] = narrowphase::split_spec(text);
  // The '+' that joins strategy and narrow phase comes before any path (a path may hold a '+').
  const std::size_t plus = head.substr(0, head.find(':')).find('+');
  const std::string name = head.substr(0, plus);
  const std::string narrow_phase = plus == std::string::npos ? std::string() : head.substr(plus + 1);
  if (name.empty() || (plus != std::string::npos && narrow_phase.empty())) throw std::invalid_argument("malformed strategy spec '" + text + "'");
  StrategySpec spec;
  spec.text = text;
  spec.entry = &find_strategy(name);
  spec.from_outside = from_outside(text);
  spec.label = short_label(text);
  const StrategyEntry& entry = *spec.entry;
  auto owns = [](const std::vector<narrowphase::KeySpec>& keys, const std::string& key) {
    return std::any_of(keys.begin(), keys.end(), [&](const narrowphase::KeySpec& k) { return k.name == key; });
  };
  if (!entry.takes_narrow_phase) {
    if (!narrow_phase.empty())
      throw std::invalid_argument(entry.name + " uses elementary tests of its own and takes no narrow phase ('" + text + "')");
    spec.own = std::move(parameters);
    return spec;
  }
  spec.narrow = &narrowphase::find_narrow_phase(narrow_phase.empty() ? narrowphase::kDefaultNarrowPhase : narrow_phase);
  const narrowphase::NarrowPhaseEntry& narrow = *spec.narrow;
  // Each key to its owner; one that neither has is refused naming both lists (so `apccd:foo=1` is not blamed on
  // the narrow phase alone).
  for (const auto& [key, value] : parameters) {
    if (owns(entry.keys, key)) {
      spec.own[key] = value;
    } else if (owns(narrow.keys, key)) {
      spec.narrow_keys[key] = value;
    } else {
      throw std::invalid_argument(entry.name + "+" + narrow.name + " has no parameter '" + key + "' (" + entry.name +
                                  "'s: " + narrowphase::key_names(entry.keys) + "; narrow phase " + narrow.name +
                                  "'s: " + narrowphase::key_names(narrow.keys) + ")");
    }
  }
  return spec;
}

namespace {

/// The spec's narrow phase as a strategy needs to know it (an empty one for a strategy with tests of its own).
narrowphase::ResolvedNarrowPhase narrow_of(const StrategySpec& spec) {
  if (!spec.narrow) return {};
  return narrowphase::resolve_narrow_phase(*spec.narrow, narrowphase::SpecReader(spec.narrow->name, spec.narrow->keys, spec.narrow_keys));
}

const StrategyEntry& available(const StrategySpec& spec) {
  if (!spec.entry->unavailable.empty()) throw std::invalid_argument(spec.entry->name + " is not available: " + spec.entry->unavailable);
  return *spec.entry;
}

}  // namespace

void validate(const StrategySpec& spec) {
  const StrategyEntry& entry = available(spec);
  // Each key's value is checked as its reader is made.
  const narrowphase::SpecReader keys(entry.name, entry.keys, spec.own);
  const narrowphase::ResolvedNarrowPhase narrow = narrow_of(spec);
  if (entry.check) entry.check(keys, narrow);
}

std::string resolved_name(const StrategySpec& spec) {
  const StrategyEntry& entry = available(spec);
  const narrowphase::SpecReader keys(entry.name, entry.keys, spec.own);
  return entry.resolve(keys, narrow_of(spec));
}

void check_scene(const StrategySpec& spec, const Scene& scene) {
  if (spec.entry->check_scene) spec.entry->check_scene(narrowphase::SpecReader(spec.entry->name, spec.entry->keys, spec.own), scene);
}

StrategyNames strategy_names_of(const std::string& spec) {
  std::string head = spec.substr(0, spec.find(':'));
  const std::size_t plus = head.find('+');  // before the first ':', so never inside a path
  // plugin:PATH and answers:DIR keep their path (split_spec's rule), before or after the '+'.
  if (narrowphase::is_file_head(head.substr(plus == std::string::npos ? 0 : plus + 1)) && head.size() < spec.size()) {
    const std::size_t end = spec.find(':', head.size() + 1);
    head = spec.substr(0, end);
  }
  return {head.substr(0, plus), plus == std::string::npos ? std::string() : head.substr(plus + 1)};
}

bool from_outside(const std::string& spec) {
  const StrategyNames names = strategy_names_of(spec);
  return narrowphase::is_file_head(names.name.substr(0, names.name.find(':'))) ||
         narrowphase::is_file_head(names.narrow_phase.substr(0, names.narrow_phase.find(':')));
}

namespace {

/// Whether the strategy or the narrow phase of a spec or resolved name has the head `head` (plugin, callable).
bool has_head(const std::string& spec, const char* head) {
  const StrategyNames names = strategy_names_of(spec);
  auto is = [&](const std::string& name) { return name.substr(0, name.find(':')) == head; };
  return is(names.name) || is(names.narrow_phase);
}

}  // namespace

bool runs_host_method(const std::string& spec) { return has_head(spec, narrowphase::kHostMethodHead); }

bool runs_plugin(const std::string& spec) { return has_head(spec, narrowphase::kPluginHead); }

std::string short_label(const std::string& spec) {
  const StrategyNames names = strategy_names_of(spec);
  auto shorten = [](const std::string& name) {
    const std::size_t colon = name.find(':');
    if (colon == std::string::npos || !narrowphase::is_file_head(name.substr(0, colon))) return name;
    return name.substr(0, colon + 1) + std::filesystem::path(name.substr(colon + 1)).filename().string();
  };
  return shorten(names.name) + (names.narrow_phase.empty() ? "" : "+" + shorten(names.narrow_phase));
}

const StrategyEntry& strategy_entry_of(const std::string& spec) { return find_strategy(strategy_names_of(spec).name); }

std::unique_ptr<Strategy> make_strategy(const StrategySpec& spec) {
  const StrategyEntry& entry = available(spec);
  const narrowphase::SpecReader keys(entry.name, entry.keys, spec.own);
  if (!spec.narrow) return entry.make({keys, nullptr});
  const narrowphase::NarrowPhaseEntry& narrow = *spec.narrow;
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase = narrow.make(narrowphase::SpecReader(narrow.name, narrow.keys, spec.narrow_keys));
  std::vector<std::pair<std::string, std::string>> notes = narrow_phase->provenance();
  const std::string why = narrow_phase->thread_safe() ? "" : "narrow phase " + narrow.name + " may not be called from several threads at once";
  if (!notes.empty() || !why.empty())
    return std::make_unique<WithNarrowPhaseNotes>(entry.make({keys, std::move(narrow_phase)}), std::move(notes), why);
  return entry.make({keys, std::move(narrow_phase)});
}

std::unique_ptr<Strategy> make_strategy(const std::string& text) { return make_strategy(parse_strategy_spec(text)); }

}  // namespace ccd::strategies
