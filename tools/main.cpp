// solo: one binary, one subcommand per job. This is the only file that sees CLI11;
// each subcommand fills an options struct (commands.h) and calls its run function.

#include "commands.h"

#include <solo/geometry/error.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>

int main(int argc, char** argv) {
  using namespace solo::tools;
  CLI::App app{"solo: turns a daytime street photo into a physically based night image"};
  app.require_subcommand(1);
  app.set_version_flag("--version", [] { return versionText(); }, "Print solo's version and its libraries' versions");

  InfoOptions info;
  CLI::App* info_cmd = app.add_subcommand("info", "Load and validate a scene; print what was read");
  info_cmd->add_option("scene", info.scene, "Scene manifest (JSON)")->required();
  info_cmd->add_flag("--json", info.json, "Print the input report as JSON");

  NightOptions night;
  CLI::App* night_cmd = app.add_subcommand("night", "Convert a day scene to night (default: the embedded scene)");
  night_cmd->add_option("scene", night.scene, "Scene manifest (JSON); omit for the embedded default scene");
  night_cmd->add_option("-o,--output", night.output, "Night image to write")->capture_default_str();
  night_cmd->add_option("--report", night.report, "Report JSON to write (default: <output>.report.json)");
  night_cmd->add_option("--seed", night.seed, "Random seed")->capture_default_str();

  ConvertOptions convert;
  CLI::App* convert_cmd = app.add_subcommand("convert", "Convert a depth or normal map between formats");
  convert_cmd->add_option("kind", convert.kind, "depth or normals")->required()->check(CLI::IsMember({"depth", "normals"}));
  convert_cmd->add_option("input", convert.input, "Input map (PNG, EXR, TIFF, PFM, NPY)")->required();
  convert_cmd->add_option("output", convert.output, "Output map; format from the extension")->required();
  convert_cmd->add_option("--input-scale", convert.input_scale_m_per_unit, "Metres per unit of an integer depth input");
  convert_cmd->add_option("--output-scale", convert.output_scale_m_per_unit, "Metres per unit of a 16-bit PNG depth output")
      ->capture_default_str();

  CLI::App* eval_cmd = app.add_subcommand("eval", "Evaluate depth, normals or a mesh (docs/evaluation.md)");
  eval_cmd->require_subcommand(1);
  const auto add_eval_output = [](CLI::App* cmd, EvalOutputOptions& output) {
    cmd->add_flag("--json", output.json, "Print the results as JSON on stdout instead of a table");
    cmd->add_option("--csv", output.csv, "Append one row of results to this CSV file (header when the file is new)");
  };
  EvalDepthOptions eval_depth;
  CLI::App* eval_depth_cmd = eval_cmd->add_subcommand("depth", "AbsRel, SqRel, RMSE, RMSElog, delta < 1.25^k");
  eval_depth_cmd->add_option("--pred", eval_depth.prediction, "Predicted depth map")->required();
  eval_depth_cmd->add_option("--gt", eval_depth.ground_truth, "Ground-truth depth map")->required();
  eval_depth_cmd->add_option("--mask", eval_depth.mask, "Mask (8/16-bit or integer): non-zero pixels are evaluated");
  eval_depth_cmd->add_option("--min-depth", eval_depth.min_depth_m, "Evaluate only where ground truth > this (m)");
  eval_depth_cmd->add_option("--max-depth", eval_depth.max_depth_m, "Evaluate only where ground truth < this (m)");
  eval_depth_cmd->add_flag("--median-scale", eval_depth.median_scaling,
                           "Scale the prediction by median(gt)/median(pred)");
  eval_depth_cmd->add_flag("--clamp-pred", eval_depth.clamp_prediction,
                           "Clamp the prediction into [min-depth, max-depth] after scaling (Monodepth2, BTS)");
  eval_depth_cmd->add_option("--pred-scale", eval_depth.prediction_scale_m_per_unit,
                             "Metres per unit of an integer prediction file");
  eval_depth_cmd->add_option("--gt-scale", eval_depth.ground_truth_scale_m_per_unit,
                             "Metres per unit of an integer ground-truth file");
  add_eval_output(eval_depth_cmd, eval_depth.output);

  EvalNormalsOptions eval_normals;
  CLI::App* eval_normals_cmd =
      eval_cmd->add_subcommand("normals", "Angular error of normals: mean, median, RMSE, shares");
  eval_normals_cmd->add_option("--pred", eval_normals.prediction, "Predicted normal map")->required();
  eval_normals_cmd->add_option("--gt", eval_normals.ground_truth, "Ground-truth normal map")->required();
  eval_normals_cmd->add_option("--mask", eval_normals.mask,
                               "Mask (8/16-bit or integer): non-zero pixels are evaluated");
  add_eval_output(eval_normals_cmd, eval_normals.output);

  EvalMeshOptions eval_mesh;
  CLI::App* eval_mesh_cmd =
      eval_cmd->add_subcommand("mesh", "Topology, defects, triangle quality, distance to a reference");
  eval_mesh_cmd->add_option("mesh", eval_mesh.mesh, "Mesh (OFF, OBJ, PLY, STL)")->required();
  eval_mesh_cmd->add_option("--ref", eval_mesh.reference, "Reference mesh for the Hausdorff and Chamfer distances");
  eval_mesh_cmd->add_option("--samples", eval_mesh.samples, "Random surface points per direction")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}));
  eval_mesh_cmd->add_option("--seed", eval_mesh.seed, "Seed of the surface sampling")->capture_default_str();
  add_eval_output(eval_mesh_cmd, eval_mesh.output);

  SynthOptions synth;
  std::string synth_size = "960x540";
  CLI::App* synth_cmd = app.add_subcommand("synth", "Generate a synthetic street scene with exact ground truth");
  synth_cmd->add_option("-o,--output", synth.output, "Folder to create")->required();
  synth_cmd->add_option("--seed", synth.seed, "Random seed")->capture_default_str();
  synth_cmd->add_option("--size", synth_size, "Image size WIDTHxHEIGHT in pixels")->capture_default_str();
  synth_cmd->add_option("--variant", synth.variant, "default, grazing, thin-pole, near-object, wide-sky, no-lights")
      ->capture_default_str();
  synth_cmd->add_flag("--force", synth.force, "Replace the output folder if it exists");

  CLI11_PARSE(app, argc, argv);
  if (synth_cmd->parsed() && std::sscanf(synth_size.c_str(), "%dx%d", &synth.width, &synth.height) != 2) {
    std::cerr << "solo: error: --size: expected WIDTHxHEIGHT, got \"" << synth_size << "\"\n";
    return 2;
  }
  try {
    if (info_cmd->parsed()) return runInfo(info);
    if (night_cmd->parsed()) return runNight(night);
    if (convert_cmd->parsed()) return runConvert(convert);
    if (eval_depth_cmd->parsed()) return runEvalDepth(eval_depth);
    if (eval_normals_cmd->parsed()) return runEvalNormals(eval_normals);
    if (eval_mesh_cmd->parsed()) return runEvalMesh(eval_mesh);
    if (synth_cmd->parsed()) return runSynth(synth);
  } catch (const solo::InputError& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 1;
  }
  return 1;
}
