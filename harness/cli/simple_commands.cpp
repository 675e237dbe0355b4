// The commands that describe: inspect, scenes, strategies, devices; and generate.
#include "harness/cli/cli.hpp"
#include "harness/commands.hpp"
#include "harness/registry_listing.hpp"

#include <iostream>
#include <memory>

namespace ccd::cli {

Command add_inspect(CLI::App& app) {
  auto options = std::make_shared<harness::InspectOptions>();
  CLI::App* inspect = app.add_subcommand("inspect",
                                         "Print what a file or folder holds: counts of vertices, faces, edges, frames, steps, queries and truth\n"
                                         "positives, and the largest vertex displacement of every step. PATH may be a mesh (.ply/.obj), a frame\n"
                                         "folder or printf pattern (frame_%04d.ply), a scene file (.json, or a folder with scene.json), a\n"
                                         "Scalable-CCD sample step folder, a query file (.csv) or folder, a truth file (mma_bool/*.json), a\n"
                                         "candidate file (boxes/*.json) or a frame cache.");
  inspect->add_option("PATH", options->paths, "files or folders to describe")->required();
  inspect->add_flag("--json", options->json, "print one JSON object per PATH (one per line) instead of text");
  return {inspect, [options] { return harness::run_inspect(*options, std::cout); }};
}

Command add_scenes(CLI::App& app) {
  CLI::App* scenes = app.add_subcommand("scenes", "List the built-in procedural scenes, their parameters and defaults.");
  return {scenes, [] { return harness::run_scenes(std::cout); }};
}

Command add_strategies(CLI::App& app) {
  struct Options {
    bool json = false;
    std::vector<std::string> plugins;
  };
  auto options = std::make_shared<Options>();
  CLI::App* strategies = app.add_subcommand("strategies",
                                            "List the strategies and narrow phases (the registries): what each is, its keys with their values and\n"
                                            "defaults, its backends, and for a strategy what it is judged by and its speed-up baseline.");
  strategies->add_flag("--json", options->json, "print one JSON object ({strategies, narrow_phases}) for scripts");
  strategies->add_option("--plugin", options->plugins, "also list this plugin (a shared library, docs/audit.md) with its keys");
  return {strategies, [options] { return harness::run_strategies(options->json, std::cout, options->plugins); }};
}

Command add_devices(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* devices =
      app.add_subcommand("devices",
                         "List the OpenCL platforms and devices: index (for full:backend=opencl:device=INDEX), name, compute units,\n"
                         "memory, and fp64 (required: the narrow phases are double precision, subnormals kept). Without device=, the\n"
                         "first GPU is used, else device 0. PoCL's CPU device is always there once pocl-opencl-icd is installed.");
  devices->add_flag("--json", *json, "one JSON object per device, one per line");
  return {devices, [json] { return harness::run_devices(*json, std::cout); }};
}

Command add_generate(CLI::App& app) {
  auto options = std::make_shared<harness::GenerateOptions>();
  CLI::App* generate = app.add_subcommand("generate",
                                          "Simulate a built-in scene into a folder: scene.json and one PLY per object per frame\n"
                                          "(OBJECT/frame_0000.ply, ...). The same parameters give bit-identical frames on any thread count, and a\n"
                                          "second call with the same parameters reads the folder's cache instead of simulating again.");
  generate->add_option("NAME", options->name, "scene name (see `ccdbench scenes`)")->required();
  generate->add_option("--resolution", options->resolution, "cloth grid side N (N x N vertices)");
  generate->add_option("--frames", options->frames, "number of frames");
  generate->add_option("--seed", options->seed, "random seed");
  generate->add_option("--first-frame", options->first_frame,
                       "first frame written (the earlier ones are simulated, not written): a scene's late, contact-rich\n"
                       "stretch without its fall, e.g. --frames 30 --first-frame 26 writes 4 frames (3 steps)");
  generate->add_option("--set", options->settings, "any scene parameter, NAME=VALUE (repeatable)");
  generate->add_option("--out", options->out, "output folder")->required();
  generate->add_flag("--report", options->report, "print the scene's measurements for every frame");
  return {generate, [options] { return harness::run_generate(*options, std::cout); }};
}

}  // namespace ccd::cli
