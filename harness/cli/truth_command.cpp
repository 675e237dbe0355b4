// ccdbench truth: the exact whole-step truth of one step, or of a scene's steps into the truth cache.
#include "harness/cli/cli.hpp"
#include "harness/commands.hpp"

#include <iostream>
#include <limits>
#include <memory>

namespace ccd::cli {

Command add_truth(CLI::App& app) {
  auto options = std::make_shared<harness::TruthOptions>();
  CLI::App* truth = app.add_subcommand("truth",
                                       "Exact whole-step truth: every vertex-face and edge-edge pair that comes within the thickness during the\n"
                                       "step, found by a certified sort-and-sweep of swept boxes and decided by the reference (certified\n"
                                       "filter, then exact root isolation). Prints the colliding counts and how the pairs were decided.");
  truth->add_option("--frames", options->frames, "two mesh files: the step's first and last frame")->expected(2);
  truth->add_option("--scene", options->scene, "a scene file (or folder with scene.json)");
  truth->add_option("--step", options->step, "step K of the scene: frame K -> K+1")->capture_default_str();
  truth
      ->add_option("--steps", options->steps,
                   "with --scene: N steps from --step on (0: to the last), each stored in the truth cache that `run`\n"
                   "reads; prints a table of every step (under mpirun, the steps are spread over the ranks)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 40))
      ->capture_default_str();
  truth->add_option("--sample", options->sample, "a Scalable-CCD sample step folder: also compare with its own truth");
  truth->add_option("--thickness", options->thickness, "thickness δ >= 0 (default: the scene's; 0 for --frames and --sample)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::max()));
  truth->add_flag("--toi", options->toi, "also compute every colliding pair's earliest contact time exactly");
  truth->add_option("--json", options->json, "also write the counts and statistics as JSON to this file");
  return {truth, [options] { return harness::run_truth(*options, std::cout); }, true};
}

}  // namespace ccd::cli
