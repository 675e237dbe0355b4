#include "strategies/plugin/plugin_narrow_phase.hpp"

#include "strategies/plugin/call_guard.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/library.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>

namespace ccd::plugin {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class PluginNarrowPhase final : public narrowphase::NarrowPhase {
 public:
  PluginNarrowPhase(const PluginDescription& description, const narrowphase::SpecReader& keys) : plugin_(description, keys) {}

  std::string name() const override { return plugin_.name(); }
  bool conservative() const override { return plugin_.description.conservative(); }
  /// Isolated, its child answers one request at a time, in the order the parent sends them (strategies send batches
  /// from one thread, in pair order): the parent may call it from any thread.
  bool thread_safe() const override { return plugin_.description.thread_safe() || plugin_.host.isolate; }
  std::vector<std::pair<std::string, std::string>> provenance() const override { return plugin_.provenance(); }

  narrowphase::NarrowPhaseResult vertex_face(const narrowphase::PairRows& rows, double thickness) const override {
    return answer(true, rows, thickness);
  }
  narrowphase::NarrowPhaseResult edge_edge(const narrowphase::PairRows& rows, double thickness) const override {
    return answer(false, rows, thickness);
  }

  /// Isolated, a batch is one round trip to the child (query_batch.hpp) instead of one per pair.
  bool prefers_batches() const override { return plugin_.isolated != nullptr; }
  void answer_batch(std::span<const BatchPair> pairs, std::span<narrowphase::NarrowPhaseResult> results) const override {
    if (!plugin_.isolated) {
      NarrowPhase::answer_batch(pairs, results);
      return;
    }
    std::vector<double> flat(24 * pairs.size());
    std::vector<IsolatedPlugin::Query> asked(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      double* rows = flat.data() + 24 * i;
      for (int p = 0; p < 8; ++p) {
        for (int c = 0; c < 3; ++c) rows[3 * p + c] = (*pairs[i].rows)[static_cast<std::size_t>(p)][c];
      }
      asked[i] = {rows, pairs[i].thickness, pairs[i].vertex_face};
    }
    const std::vector<ccdbench_answer> answers = plugin_.isolated->queries(asked);
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      results[i] = checked_answer(answers[i], plugin_.description.reports_toi(), plugin_.host.errors_count_as_hits);
    }
  }

 private:
  narrowphase::NarrowPhaseResult answer(bool vertex_face, const narrowphase::PairRows& rows, double thickness) const {
    double flat[24];
    for (int p = 0; p < 8; ++p) {
      for (int c = 0; c < 3; ++c) flat[3 * p + c] = rows[static_cast<std::size_t>(p)][c];
    }
    ccdbench_answer answer;
    if (plugin_.isolated) {
      answer = plugin_.isolated->query(vertex_face, flat, thickness);
    } else {
      // Only what the plugin writes into this answer counts: it starts with no outcome, so a plugin that writes
      // none is caught, and nothing from an earlier call can leak into it.
      std::memset(&answer, 0, sizeof answer);
      answer.outcome = -1;
      answer.toi = kNaN;
      const ccdbench_plugin& table = plugin_.library->table();
      std::unique_lock lock(plugin_.context->mutex(), std::defer_lock);
      if (!plugin_.description.thread_safe()) lock.lock();
      const std::string fault = guarded_call(plugin_.context->call_site(), vertex_face ? "a vertex-face query" : "an edge-edge query", [&] {
        (vertex_face ? table.vertex_face : table.edge_edge)(plugin_.context->handle(), flat, thickness, &answer);
      });
      if (!fault.empty()) {
        // Whatever it answered, the call did something else too: it is the call's error, never an answer.
        answer.outcome = CCDBENCH_ERROR;
        std::snprintf(answer.message, CCDBENCH_MESSAGE_SIZE, "%s", fault.c_str());
      }
    }
    return checked_answer(answer, plugin_.description.reports_toi(), plugin_.host.errors_count_as_hits);
  }

  PluginInstance plugin_;
};

}  // namespace

bool names_plugin(const std::string& name) { return name.rfind(std::string(narrowphase::kPluginHead) + ":", 0) == 0; }

narrowphase::NarrowPhaseResult checked_answer(const ccdbench_answer& answer, bool reports_toi, bool errors_count_as_hits) {
  narrowphase::NarrowPhaseResult result;
  auto message = [&] { return std::string(answer.message, strnlen(answer.message, CCDBENCH_MESSAGE_SIZE)); };
  switch (answer.outcome) {
    case CCDBENCH_APART: return result;
    case CCDBENCH_CONTACT:
      if (!reports_toi) {
        result.collides = true;
        return result;
      }
      if (std::isnan(answer.toi)) {
        result.fault = "a contact with a TOI that is not a number";
      } else if (!(answer.toi >= 0.0 && answer.toi <= 1.0)) {
        result.fault = "a contact with TOI " + narrowphase::format_spec_number(answer.toi) + ", not in [0, 1]";
      } else {
        result.collides = true;
        result.toi = answer.toi;
        return result;
      }
      break;
    case CCDBENCH_UNDECIDED: result.fault = "undecided: " + message(); break;
    case CCDBENCH_ERROR: result.fault = "error: " + message(); break;
    default: result.fault = "outcome " + std::to_string(answer.outcome) + " is none of the ABI's (0 apart, 1 contact, 2 undecided, 3 error)";
  }
  // A fault counts as the plugin's `errors` key says; as a hit, at the start of the step (never late).
  result.collides = errors_count_as_hits;
  if (errors_count_as_hits && reports_toi) result.toi = 0.0;
  return result;
}

narrowphase::NarrowPhaseEntry narrow_phase_entry(const std::string& name) {
  const std::string path = name.substr(std::strlen(narrowphase::kPluginHead) + 1);
  const PluginDescription& description = plugin_description(path);
  if (!description.answers_queries()) {
    throw std::invalid_argument("plugin " + description.path + " answers whole steps, not queries: run it as --strategy " + name +
                                " (its whole step), not as a narrow phase");
  }
  narrowphase::NarrowPhaseEntry entry;
  entry.name = name;
  entry.help = description.description();
  entry.keys = entry_keys(description);
  entry.conservative = description.conservative();
  entry.make = [&description](const narrowphase::SpecReader& keys) -> std::unique_ptr<narrowphase::NarrowPhase> {
    return std::make_unique<PluginNarrowPhase>(description, keys);
  };
  entry.resolve = [&description](const narrowphase::SpecReader& keys) {
    return resolved_name(description, plugin_values(keys, description), read_host_settings(keys, description));
  };
  return entry;
}

}  // namespace ccd::plugin
