#include "harness/run/faults.hpp"

#include "datasets/atomic_file.hpp"
#include "datasets/ply.hpp"
#include "datasets/query_file.hpp"
#include "harness/timed_region.hpp"
#include "reference/elementary_pair.hpp"

#include <gmpxx.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace ccd::harness {
namespace {

/// δ as the shortest text that reads back as it.
std::string number_text(double value) {
  char text[64];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

}  // namespace

nlohmann::json record_faults(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<strategies::StepResult>& results,
                             const std::filesystem::path& directory, const std::string& spec) {
  harness_pass("fault records");
  std::size_t count = 0;
  for (const strategies::StepResult& result : results) count += result.fault_count;
  if (count == 0) return {{"errors", 0}};
  std::ostringstream notes;
  notes << count << " answers could not be taken; each step keeps its first " << strategies::kKeptFaults << ".\n";
  for (std::size_t k = 0; k < results.size(); ++k) {
    const strategies::StepResult& result = results[k];
    if (result.fault_count == 0) continue;
    const std::filesystem::path step = directory / ("step_" + std::to_string(k));
    notes << "\nstep " << k << ": " << result.fault_count << "\n";
    std::vector<datasets::Query> vertex_face, edge_edge;
    bool whole_step = false;
    for (const strategies::Fault& fault : result.faults) {
      if (!fault.rows) {
        whole_step = true;
        notes << "  " << fault.message << "  [" << (step / "frame_0.ply").string() << ", frame_1.ply]\n";
        continue;
      }
      datasets::Query query = datasets::query_of_doubles(*fault.rows);
      // Labelled by the reference at the scene's δ, so that the replay scores what the run could not.
      const auto kind = fault.vertex_face ? reference::PairKind::vertex_face : reference::PairKind::edge_edge;
      query.truth = reference::decide(kind, *fault.rows, scene.thickness(), {}).collides;
      std::vector<datasets::Query>& list = fault.vertex_face ? vertex_face : edge_edge;
      list.push_back(std::move(query));
      notes << "  " << fault.message << "  [" << (step / (fault.vertex_face ? "vertex-face" : "edge-edge") / "errors.csv").string() << ", query "
            << list.size() << "]\n";
    }
    if (!vertex_face.empty()) datasets::write_query_file(step / "vertex-face" / "errors.csv", vertex_face, scene.thickness());
    if (!edge_edge.empty()) datasets::write_query_file(step / "edge-edge" / "errors.csv", edge_edge, scene.thickness());
    if (!vertex_face.empty() || !edge_edge.empty()) {
      // The narrow phase of a `NAME+NARROW` spec answers the queries on its own (a whole-step plugin has none).
      const std::size_t plus = spec.find('+');
      const std::string method = plus == std::string::npos ? spec : spec.substr(plus + 1);
      notes << "  replay: ccdbench queries " << step.string() << " --method " << method << " --thickness " << number_text(scene.thickness()) << "\n";
    }
    if (whole_step) {
      // The whole mesh as one object: the step's positions, to replay with --frames (δ as the scene's).
      const std::vector<Face>& faces = scene.topology().faces();
      datasets::write_ply(step / "frame_0.ply", {frames[k], faces, {}});
      datasets::write_ply(step / "frame_1.ply", {frames[k + 1], faces, {}});
      notes << "  replay: ccdbench run --frames " << (step / "frame_0.ply").string() << " " << (step / "frame_1.ply").string() << " --thickness "
            << number_text(scene.thickness()) << " --strategy " << spec << "\n";
    }
  }
  datasets::AtomicFile file(directory / "FAULTS.txt", std::ios::out);
  file.stream() << notes.str();
  file.commit();
  return {{"errors", count}, {"errors_written", directory.string()}};
}

void write_step_answers(const std::vector<strategies::StepResult>& results, const std::filesystem::path& directory) {
  harness_pass("answer files");
  auto toi = [](double t) {
    if (std::isnan(t)) return std::string();
    char text[64];
    return std::string(text, std::to_chars(text, text + sizeof text, t).ptr);  // the shortest text that reads back as t
  };
  for (std::size_t k = 0; k < results.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "step_%04zu.csv", k);
    datasets::AtomicFile file(directory / name, std::ios::out);
    std::ostream& out = file.stream();
    for (const auto& c : results[k].collisions.vertex_face()) out << "vf," << c.pair.v << ',' << c.pair.f << ',' << toi(c.toi) << '\n';
    for (const auto& c : results[k].collisions.edge_edge()) {
      out << "ee," << c.pair.a.v0 << ',' << c.pair.a.v1 << ',' << c.pair.b.v0 << ',' << c.pair.b.v1 << ',' << toi(c.toi) << '\n';
    }
    file.commit();
  }
}

}  // namespace ccd::harness
