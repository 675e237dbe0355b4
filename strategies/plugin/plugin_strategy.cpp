#include "strategies/plugin/plugin_strategy.hpp"

#include "ccd/config.hpp"
#include "core/stage_timer.hpp"
#include "strategies/plugin/call_guard.hpp"
#include "strategies/plugin/contact_check.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/library.hpp"

#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace ccd::plugin {
namespace {

/// The mesh as the ABI hands it over (ccdbench_scene), kept for as long as the plugin may read it.
struct SceneTables {
  std::vector<std::uint32_t> faces, edges, face_object, collidable;
  std::vector<std::uint8_t> self_collision;
  ccdbench_scene scene{};

  explicit SceneTables(const Scene& s) {
    const MeshTopology& topology = s.topology();
    for (const Face& face : topology.faces()) faces.insert(faces.end(), {face[0], face[1], face[2]});
    for (const Edge& edge : topology.edges()) edges.insert(edges.end(), {edge.v0, edge.v1});
    for (FaceId f = 0; f < topology.num_faces(); ++f) face_object.push_back(s.object_of_face(f));
    for (const SceneObject& object : s.objects()) self_collision.push_back(object.self_collision ? 1 : 0);
    for (const auto& [a, b] : s.collidable_pairs()) collidable.insert(collidable.end(), {a, b});
    scene = {topology.num_vertices(), topology.num_faces(), faces.data(),          topology.edges().size(),     edges.data(),
             s.objects().size(),      face_object.data(),   self_collision.data(), s.collidable_pairs().size(), collidable.data()};
  }
};

/// What a step reported, before the checks.
struct Reported {
  struct VertexFace {
    std::uint32_t v, f;
    double toi;
  };
  struct EdgeEdge {
    std::uint32_t a0, a1, b0, b1;
    double toi;
  };
  std::vector<VertexFace> vertex_face;
  std::vector<EdgeEdge> edge_edge;
};

void refuse_plugin_shapes(const std::string& name, const Scene& scene) { refuse_shapes(name, scene, "the plugin ABI has no analytic shapes"); }

class WholeStepPlugin final : public strategies::Strategy {
 public:
  WholeStepPlugin(const PluginDescription& description, const narrowphase::SpecReader& keys) : plugin_(description, keys) {}
  ~WholeStepPlugin() override { finish(); }

  std::string name() const override { return plugin_.name(); }

  void check_scene(const Scene& scene) const override { refuse_plugin_shapes(name(), scene); }

  void init(const Scene& scene, std::span<const Vec3>) override {
    check_scene(scene);
    finish();
    tables_ = std::make_unique<SceneTables>(scene);
    check_ = std::make_unique<ContactCheck>(scene, plugin_.description.reports_toi() ? ContactCheck::Toi::required : ContactCheck::Toi::ignored);
    begin_error_.clear();
    std::string message;
    int status = 0;
    if (plugin_.isolated) {
      status = plugin_.isolated->begin(tables_->scene, message);
    } else if (plugin_.library->table().begin) {
      char error[CCDBENCH_MESSAGE_SIZE] = {};
      const std::string fault = guarded_call(plugin_.context->call_site(), "begin",
                                             [&] { status = plugin_.library->table().begin(plugin_.context->handle(), &tables_->scene, error); });
      message.assign(error, strnlen(error, CCDBENCH_MESSAGE_SIZE));
      if (!fault.empty()) {
        status = 1;
        message = fault;
      }
    }
    // A plugin that refuses the scene answers no step: each step is then its fault (the run goes on).
    if (status != 0) begin_error_ = "begin failed: " + (message.empty() ? std::string("no reason given") : message);
    begun_ = true;
  }

  strategies::StepResult step(const StepView& view, bool /*audit*/) override {
    static_assert(sizeof(Vec3) == 3 * sizeof(double), "positions are handed over as 3 doubles per vertex, in place");
    strategies::StepResult result;
    if (!begin_error_.empty()) {
      add_step_fault(result, begin_error_);
      return result;
    }
    Reported reported;
    std::string message;
    int status = 0;
    const double* x0 = view.x0.data()->data();
    const double* x1 = view.x1.data()->data();
#if CCDBENCH_GUARD_INPUT_COPIES
    if (!plugin_.isolated) {
      // In-process the plugin gets copies: what it writes through its const pointers changes no frame of the run
      // (isolated, the positions cross a pipe anyway).
      ScopedStageTimer timer(result.stages, "copy positions");
      x0_copy_.assign(x0, x0 + 3 * view.x0.size());
      x1_copy_.assign(x1, x1 + 3 * view.x1.size());
      x0 = x0_copy_.data();
      x1 = x1_copy_.data();
    }
#endif
    {
      ScopedStageTimer timer(result.stages, "plugin step");
      const ccdbench_step step{view.index, x0, x1, view.scene->thickness()};
      const ccdbench_contacts contacts{&reported,
                                       [](void* host, std::uint32_t v, std::uint32_t f, double toi) {
                                         static_cast<Reported*>(host)->vertex_face.push_back({v, f, toi});
                                       },
                                       [](void* host, std::uint32_t a0, std::uint32_t a1, std::uint32_t b0, std::uint32_t b1, double toi) {
                                         static_cast<Reported*>(host)->edge_edge.push_back({a0, a1, b0, b1, toi});
                                       }};
      if (plugin_.isolated) {
        status = plugin_.isolated->step(step, view.x0.size(), contacts, message);
      } else {
        char error[CCDBENCH_MESSAGE_SIZE] = {};
        const std::string fault = guarded_call(plugin_.context->call_site(), "its step",
                                               [&] { status = plugin_.library->table().step(plugin_.context->handle(), &step, &contacts, error); });
        message.assign(error, strnlen(error, CCDBENCH_MESSAGE_SIZE));
        if (!fault.empty()) {
          status = 1;
          message = fault;
        }
      }
    }
    if (status != 0) {
      // A failed step reports nothing: what it sent before failing is not an answer.
      add_step_fault(result, "step " + std::to_string(view.index) + " failed: " + (message.empty() ? std::string("no reason given") : message));
      return result;
    }
    ScopedStageTimer timer(result.stages, "check answers");
    check_->reset();
    std::string why;
    const MeshTopology& topology = view.scene->topology();
    for (Reported::VertexFace c : reported.vertex_face) {
      if (auto pair = check_->vertex_face(c.v, c.f, c.toi, why)) {
        result.collisions.add(*pair, c.toi);
      } else {
        add_fault(result, why,
                  c.v < topology.num_vertices() && c.f < topology.num_faces()
                      ? std::optional(pair_rows(topology, view.x0, view.x1, VertexFacePair{c.v, c.f}))
                      : std::nullopt,
                  true);
      }
    }
    for (Reported::EdgeEdge c : reported.edge_edge) {
      if (auto pair = check_->edge_edge(c.a0, c.a1, c.b0, c.b1, c.toi, why)) {
        result.collisions.add(*pair, c.toi);
      } else {
        const std::size_t n = topology.num_vertices();
        const bool in_range = c.a0 < n && c.a1 < n && c.b0 < n && c.b1 < n;
        add_fault(result, why,
                  in_range ? std::optional(pair_rows(topology, view.x0, view.x1, EdgeEdgePair{{c.a0, c.a1}, {c.b0, c.b1}})) : std::nullopt, false);
      }
    }
    result.collisions.normalize();
    result.counters.elementary_tests = reported.vertex_face.size() + reported.edge_edge.size();
    return result;
  }

  std::vector<std::pair<std::string, std::string>> provenance() const override { return plugin_.provenance(); }

 private:
  static void add_fault(strategies::StepResult& result, const std::string& why, std::optional<std::array<Vec3, 8>> rows, bool vertex_face) {
    ++result.fault_count;
    if (result.faults.size() < strategies::kKeptFaults) result.faults.push_back({why, rows, vertex_face});
  }
  static void add_step_fault(strategies::StepResult& result, const std::string& why) { add_fault(result, why, std::nullopt, true); }

  void finish() {
    if (!begun_) return;
    begun_ = false;
    if (plugin_.isolated) {
      plugin_.isolated->end();
    } else if (plugin_.library->table().end) {
      // Nothing is answered any more: what end does beside its job can only be said.
      const std::string fault = guarded_call(plugin_.context->call_site(), "end", [&] { plugin_.library->table().end(plugin_.context->handle()); });
      if (!fault.empty()) std::fprintf(stderr, "ccdbench: warning: %s: end: %s\n", plugin_.context->call_site().plugin.c_str(), fault.c_str());
    }
  }

  PluginInstance plugin_;
  std::unique_ptr<SceneTables> tables_;
  std::unique_ptr<ContactCheck> check_;
  std::string begin_error_;
  bool begun_ = false;
  std::vector<double> x0_copy_, x1_copy_;
};

}  // namespace

strategies::StrategyEntry whole_step_entry(const std::string& name) {
  const std::string path = name.substr(std::strlen(narrowphase::kPluginHead) + 1);
  const PluginDescription& description = plugin_description(path);
  if (!description.answers_steps()) {
    throw std::invalid_argument("plugin " + description.path + " answers queries, not whole steps: run it as a narrow phase (--strategy full+" +
                                name + ", or apccd+" + name + ")");
  }
  strategies::StrategyEntry entry;
  entry.name = name;
  entry.help = description.description();
  entry.keys = entry_keys(description);
  entry.takes_narrow_phase = false;
  // Its misses have one cause ccdbench can tell: the plugin did not report the pair (it tests no pair ccdbench sees).
  entry.explain_miss = [](const narrowphase::PairRows&, bool) { return std::string("unreported"); };
  entry.make = [&description](strategies::StrategyRequest request) -> std::unique_ptr<strategies::Strategy> {
    return std::make_unique<WholeStepPlugin>(description, request.keys);
  };
  entry.resolve = [&description](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase&) {
    return resolved_name(description, plugin_values(keys, description), read_host_settings(keys, description));
  };
  // Its digest and ccdbench's own keys, checked without loading it (a stale digest= is refused before any work).
  entry.check = [&description](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase&) {
    read_host_settings(keys, description);
  };
  entry.check_scene = [name](const narrowphase::SpecReader&, const Scene& scene) { refuse_plugin_shapes(name, scene); };
  return entry;
}

}  // namespace ccd::plugin
