// solo: one binary, one subcommand per job. This is the only file that sees CLI11;
// each subcommand fills an options struct (commands.h) and calls its run function.

#include "commands.h"

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/normal_guided_objective.h>
#include <solo/pipeline/large_buffer_allocator.h>
#include <solo/pipeline/night_batch.h>
#include <solo/pipeline/night_presets.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/fog_glare.h>
#include <solo/render/light_sampler.h>
#include <solo/render/sampler.h>

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <filesystem>
#include <map>
#include <new>
#include <memory>

namespace {

const std::map<std::string, solo::LightSamplerKind> kLightSamplers = {{"uniform", solo::LightSamplerKind::Uniform},
                                                                      {"power", solo::LightSamplerKind::Power},
                                                                      {"hierarchy", solo::LightSamplerKind::Hierarchy}};
const std::map<std::string, solo::SamplerKind> kSamplers = {{"sobol", solo::SamplerKind::Sobol},
                                                            {"independent", solo::SamplerKind::Independent}};
const std::map<std::string, solo::GlareMethod> kGlareMethods = {{"auto", solo::GlareMethod::Automatic},
                                                                {"direct", solo::GlareMethod::Direct},
                                                                {"fft", solo::GlareMethod::Fft},
                                                                {"tiled", solo::GlareMethod::TiledFft}};
const std::map<std::string, solo::TransferCurve> kTransferCurves = {{"gamma2.2", solo::TransferCurve::Gamma22},
                                                                    {"srgb", solo::TransferCurve::Srgb},
                                                                    {"linear", solo::TransferCurve::Linear}};
const std::map<std::string, solo::NegativeHandling> kNegativeHandlings = {
    {"desaturate", solo::NegativeHandling::Desaturate}, {"clip", solo::NegativeHandling::Clip}};
const std::map<std::string, solo::HighlightHandling> kHighlightHandlings = {
    {"desaturate", solo::HighlightHandling::Desaturate}, {"clip", solo::HighlightHandling::Clip}};
const std::map<std::string, solo::DepthOptimizer> kDepthOptimizers = {{"ceres", solo::DepthOptimizer::Ceres},
                                                                      {"adam", solo::DepthOptimizer::Adam}};
const std::map<std::string, solo::TangentModel> kTangentModels = {{"perspective", solo::TangentModel::Perspective},
                                                                  {"paper", solo::TangentModel::PaperGraph}};

// The name `names` gives `value` (the option's default as the help shows it).
template <typename Enum>
std::string choiceName(const std::map<std::string, Enum>& names, Enum value) {
  for (const auto& [name, named] : names)
    if (named == value) return name;
  return {};
}

// An option bound to an enum: one of the names of `names`, the value's name as its default, and
// `choices` ("" or "{a,b}") as its help type instead of the enum's numbers.
template <typename Enum>
CLI::Option* namedChoice(CLI::Option* option, const std::map<std::string, Enum>& names, Enum value,
                         const std::string& choices = "") {
  return option->transform(CLI::CheckedTransformer(names).description(choices))
      ->type_name("TEXT")
      ->default_str(choiceName(names, value));
}

// A seed: decimal digits only, at most 2^64 - 1 (CLI11 alone would wrap "-1" and overflow).
const CLI::Validator kSeed(
    [](std::string& text) -> std::string {
      if (text.empty() || text.size() > 20 || text.find_first_not_of("0123456789") != std::string::npos)
        return "a seed is a whole number from 0 to 18446744073709551615, got \"" + text + "\"";
      errno = 0;
      std::strtoull(text.c_str(), nullptr, 10);
      if (errno == ERANGE) return "a seed is at most 18446744073709551615, got " + text;
      return "";
    },
    "SEED");

// A leaf command of the binary: its CLI11 subcommand and what runs when it was given.
struct Command {
  CLI::App* cli;
  std::function<int()> run;
};

// "WIDTHxHEIGHT" into its two numbers; InputError naming `option` otherwise.
void parseSize(const std::string& text, const char* option, int& width, int& height) {
  const std::size_t x = text.find('x');
  const auto side = [&](const std::string& digits, int& value) {
    if (digits.empty() || digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos)
      throw solo::InputError(option, "expected WIDTHxHEIGHT with each side 1 to 999999 pixels, got \"" + text + "\"");
    value = std::stoi(digits);
  };
  if (x == std::string::npos) throw solo::InputError(option, "expected WIDTHxHEIGHT, got \"" + text + "\"");
  side(text.substr(0, x), width);
  side(text.substr(x + 1), height);
}

using namespace solo;
using namespace solo::tools;

void addInfoCommand(CLI::App& app, std::vector<Command>& commands) {
  auto info_holder = std::make_shared<InfoOptions>();
  InfoOptions& info = *info_holder;
  CLI::App* info_cmd = app.add_subcommand("info", "Load and validate a scene; print what was read");
  info_cmd->add_option("scene", info.scene, "Scene manifest (JSON)")->required();
  info_cmd->add_flag("--json", info.json, "Print the input report as JSON");
  commands.push_back({info_cmd, [info_holder] { return runInfo(*info_holder); }});
}

// The night conversion's depth, mesh and light flags.
void addNightSceneFlags(CLI::App* night_cmd, NightOptions& night) {
  night_cmd->add_option("scene", night.job.scene, "Scene manifest (JSON); omit for the embedded default scene");
  night_cmd->add_option("-o,--output", night.job.output, "Night image to write")->capture_default_str();
  night_cmd->add_option("--report", night.job.report, "Report JSON to write (default: <output>.report.json)");
  night_cmd->add_option("--seed", night.conversion.seed, "Random seed (lights, render, sensor noise)")->capture_default_str()->check(kSeed);
  night_cmd->add_option("--render-exr", night.job.render_exr, "Also write the linear XYZ render (and AOVs beside it)");
  night_cmd->add_flag("--16bit", night.job.sixteen_bit, "16-bit PNG/TIFF output");
  night_cmd->add_flag("--refine,!--no-refine", night.conversion.refine, "Depth filter, uncertainty and optimisation (default on)");
  night_cmd->add_flag("-v,--verbose", night.verbose, "Every stage's notes on the terminal (the report has them)");
  night_cmd->add_flag("--complete,!--no-complete", night.conversion.refinement.complete,
                      "Depth completion: a depth for every pixel that is not sky (default on)");
  night_cmd->add_option("--min-depth-share", night.conversion.min_depth_share,
                        "Refuse a depth map with less than this share of its pixels holding a depth (sparser LiDAR: "
                        "densify it first, or lower this and accept the completion's guess)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  night_cmd->add_flag("--optimize,!--no-optimize", night.conversion.refinement.optimize, "Normal-guided depth optimisation (preset)");
  night_cmd->add_option("--optimize-iterations", night.conversion.refinement.optimization.max_iterations, "Its solver iterations (preset)")
      ->capture_default_str()->check(CLI::Range(1, 100000));
  night_cmd->add_option("--optimize-tolerance", night.conversion.refinement.optimization.function_tolerance,
                        "It stops when the objective decreases by less than this, relative (preset)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  night_cmd->add_flag("--solids,!--no-solids", night.conversion.mesh.close_solids, "Close foreground objects into solids (default on)");
  night_cmd->add_flag("--backdrops,!--no-backdrops", night.conversion.mesh.backdrops,
                      "Close the frame holes nothing else closes with a backdrop behind the occluders (default on)");
  night_cmd->add_flag("--evaluate-mesh,!--no-evaluate-mesh", night.conversion.mesh.evaluate,
                      "Count self-intersections and non-manifold parts (slow; preset)");
  night_cmd->add_flag("--ablation", night.conversion.lights.instantiation.ablation, "The paper's ablation: every light on, white, one strength");
  night_cmd->add_option("--lights", night.conversion.light_record, "Use this (edited) light record instead of a new draw");
  night_cmd->add_flag("--propose-lights,!--no-propose-lights", night.conversion.propose_lights,
                      "Propose lights for a scene without a light map (default on; docs/lighting.md)");
  night_cmd->add_flag("--headlights,!--no-headlights", night.conversion.night_scene.headlights, "Ego-vehicle headlights (default on)");
  night_cmd->add_flag("--shading-normals,!--no-shading-normals", night.conversion.night_scene.shading_normals,
                      "Shade faces made from pixels with the normal map's normals (default on)");
  night_cmd->add_flag("--remove-day-light,!--no-remove-day-light", night.conversion.night_scene.remove_day_light,
                      "Without an albedo map, take the day's sun and sky out of the day image (default off; docs/rendering.md)");
  night_cmd->add_flag("--day-shadows-from-image,!--day-shadows-from-rays",
                      night.conversion.night_scene.day_light.shadows_from_image,
                      "With --remove-day-light: read the sun's shadows from the image's lit and shadowed regions "
                      "(default) or trace shadow rays through the mesh (docs/rendering.md)");
  night_cmd->add_option("--headlight-flux", night.conversion.night_scene.headlight_flux_lm, "Flux of each headlight, lm")->capture_default_str();
}

// The render's flags.
void addNightRenderFlags(CLI::App* night_cmd, NightOptions& night) {
  night_cmd->add_option("--light-sampler", night.conversion.render.light_sampler, "uniform, power or hierarchy")
      ->transform(CLI::CheckedTransformer(kLightSamplers))
      ->default_str(lightSamplerName(night.conversion.render.light_sampler));
  night_cmd->add_flag("--near-field-lights,!--no-near-field-lights", night.conversion.render.near_field_lights,
                      "Mix the light sampler with near-field selection among emitters within 0.5 m (presets: off; docs/rendering.md)");
  night_cmd->add_option("--sampler", night.conversion.render.sampler,
                        "Per-sample numbers: sobol (scrambled Sobol points) or independent (PCG32)")
      ->transform(CLI::CheckedTransformer(kSamplers))
      ->default_str(samplerKindName(night.conversion.render.sampler));
  night_cmd->add_option("--min-spp", night.conversion.render.min_samples, "Samples per pixel before adaptive stopping")->capture_default_str();
  night_cmd->add_option("--max-spp", night.conversion.render.max_samples, "Samples per pixel at most")->capture_default_str();
  night_cmd->add_option("--relative-error", night.conversion.render.relative_error, "Adaptive sampling target (relative standard error)")
      ->capture_default_str();
  night_cmd->add_flag("--noise-target,!--no-noise-target", night.conversion.noise_target,
                      "Adaptive sampling to the sensor noise: stop at noise-factor x its sigma (replaces --relative-error; preset)");
  night_cmd->add_option("--noise-factor", night.conversion.render.noise_factor, "Render noise allowed, as a fraction of the sensor noise")
      ->capture_default_str();
  night_cmd->add_option("--shadow-roulette", night.conversion.render.shadow_roulette,
                        "Shadow rays of contributions below this fraction of the sensor noise at black are cast by "
                        "roulette (unbiased; with --noise-target; 0 = off; preset)")
      ->capture_default_str()->check(CLI::Range(0.0, 1.0));
  night_cmd->add_option("--max-bounces", night.conversion.render.max_bounces, "Path length limit of the tracer (preset)")
      ->capture_default_str()->check(CLI::Range(1, 64));
  night_cmd->add_option("--indirect-clamp", night.conversion.render.indirect_clamp,
                        "Clamp a sample's indirect luminance to this, cd/m2 (biased, removes fireflies); 0 = off")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  night_cmd->add_option("--mesh-downsample", night.conversion.mesh_downsample,
                        "Make the mesh from the depth downsampled by this factor; 0 = auto: 2 above 1 megapixel "
                        "(preset)")
      ->capture_default_str()->check(CLI::Range(0, 8));
  night_cmd->add_option("--render-downsample", night.conversion.render_downsample,
                        "Render at the image size divided by this factor, then upsample with the image's texture; "
                        "0 = auto: 2 above 1 megapixel (preset)")
      ->capture_default_str()->check(CLI::Range(0, 8));
  night_cmd->add_flag("--pixel-texture,!--no-pixel-texture", night.conversion.render.pixel_texture,
                      "Camera rays take their own pixel's material and light, not their mesh face's (edges between "
                      "materials along the pixels, not the mesh's quad diagonals)");
  night_cmd->add_flag("--upsample-texture,!--no-upsample-texture", night.conversion.upsample.texture,
                      "A render below the image size gets the image's texture back when upsampled; off: bilinear");
  night_cmd->add_flag("--denoise,!--no-denoise", night.conversion.denoise.enabled,
                      "Edge-aware filter of the render's Monte Carlo noise, guided by its AOVs (preset)");
  night_cmd->add_option("--firefly-sigma", night.conversion.denoise.firefly_sigma,
                        "Before denoising, scale down rare bright samples this many standard deviations above their "
                        "neighbours and spread the rest of their light wide (no blotches); 0 = off")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  night_cmd->add_option("--denoise-passes", night.conversion.denoise.iterations,
                        "A-trous passes of the render filter, taps 1, 2, ..., 2^(N-1) px apart")
      ->capture_default_str()->check(CLI::Range(1, 10));
  night_cmd->add_option("--denoise-fine-passes", night.conversion.denoise.fine_passes,
                        "Render filter passes after those, taps 2^(N-1), ..., 2, 1 px apart: they average out the "
                        "a-trous grid (blocks) around rare bright samples; 0 = none")
      ->capture_default_str()->check(CLI::Range(0, 10));
}

// The night camera's and the post-process's flags.
void addNightCameraFlags(CLI::App* night_cmd, NightOptions& night) {
  night_cmd->add_flag("--glare,!--no-glare", night.conversion.post.glare, "Fog glare (preset)");
  night_cmd->add_flag("--noise,!--no-noise", night.conversion.post.noise, "Sensor noise (preset)");
  night_cmd->add_option("--sensor-white", night.conversion.sensor_white_cd_m2,
                         "Luminance exposed to sensor white, cd/m2; 0 = the night camera's auto exposure")
      ->capture_default_str();
  night_cmd->add_option("--camera-f-number", night.conversion.camera.f_number, "Night camera: fixed aperture")
      ->capture_default_str()->check(CLI::Range(0.5, 64.0));
  night_cmd->add_option("--camera-max-shutter", night.conversion.camera.max_shutter_s,
                        "Night camera: longest exposure time, s (1/30: one frame of 30 fps video)")
      ->capture_default_str()->check(CLI::Range(1e-4, 30.0));
  night_cmd->add_option("--camera-max-iso", night.conversion.camera.max_iso,
                        "Night camera: highest ISO (100-3200, the sensor noise calibration's range)")
      ->capture_default_str()->check(CLI::Range(100.0, 3200.0));
  night_cmd->add_option("--camera-compensation", night.conversion.camera.compensation_ev,
                        "Night camera: exposure compensation of its night mode, EV")
      ->capture_default_str()->check(CLI::Range(-6.0, 6.0));
  night_cmd->add_option("--noise-scale", night.conversion.post.noise_options.std_scale, "Sensor noise standard deviation multiplier")
      ->capture_default_str()->check(CLI::Range(0.0, 10.0));
  night_cmd->add_option("--chroma-denoise", night.conversion.post.noise_options.chroma_denoise_sigma_px,
                        "Sensor noise's chroma noise reduction: Gaussian sigma in px on its colour differences, "
                        "linear and after the curve; 0 = off")
      ->capture_default_str()->check(CLI::Range(0.0, 64.0));
  night_cmd->add_option("--white-clip", night.conversion.post.encoding_options.white_clip,
                        "Video knee: linear level encoded as full white, in sensor whites (1 = clip at white)")
      ->capture_default_str()->check(CLI::Range(1.0, 64.0));
  night_cmd->add_option("--knee-point", night.conversion.post.encoding_options.knee_point, "Video knee: encoded luminance where it starts")
      ->capture_default_str()->check(CLI::Range(0.05, 0.99));
  night_cmd->add_option("--glare-scatter", night.conversion.post.glare_options.scatter_fraction,
                        "Share of a clipping pixel's excess light the lens scatters into glare (1 = the reference)")
      ->capture_default_str()->check(CLI::Range(1e-6, 1.0));
  night_cmd->add_option("--glare-threshold", night.conversion.post.glare_options.threshold,
                        "Luminance above which pixels glow (render units before exposure); -1 = what clips; "
                        "the reference uses 0")
      ->capture_default_str();
}

void addNightCommand(CLI::App& app, std::vector<Command>& commands, int argc, char** argv) {
  auto night_holder = std::make_shared<NightOptions>();
  NightOptions& night = *night_holder;
  auto batch_holder = std::make_shared<tools::NightBatchOptions>();
  tools::NightBatchOptions& night_batch = *batch_holder;
  CLI::App* night_cmd = app.add_subcommand("night", "Convert a day scene to night (default: the embedded scene)");
  addNightSceneFlags(night_cmd, night);
  addNightRenderFlags(night_cmd, night);
  addNightCameraFlags(night_cmd, night);
  night_cmd->add_option("--preset", night.preset, "Quality: draft, default or final (docs/presets.md); options "
                        "given on the command line or in the config file override it")
      ->capture_default_str()->check(CLI::IsMember(nightPresetNames()));
  night_cmd->add_option("--contact-sheet", night.job.contact_sheet,
                        "Also write a PNG grid: day, raw and refined depth, removed faces, lights, night");
  night_cmd->add_option("--write-config", night.write_config,
                        "Write the effective configuration (preset applied) to this file, then run")
      ->configurable(false);
  // CLI11 reads config files on the main app only: `solo night --config F` falls through to it.
  app.set_config("--config", "", "Config file (TOML/INI) with a [night] section; docs/presets.md");
  app.allow_config_extras(CLI::config_extras_mode::error);
  night_cmd->fallthrough();
  night_cmd->footer("Every option can also come from a config file: --config FILE, keys under [night] named like the "
                    "long options without dashes (docs/presets.md). The command line overrides the file, and "
                    "both override the preset.");
  CLI::Option* batch_opt = night_cmd->add_option(
      "--batch", night_batch.list,
      "Convert every scene of a list file (one manifest a line) or a folder; -o is then the output folder "
      "(docs/batch.md)")->configurable(false);
  night_cmd->add_option("--shard", night_batch.shard, "With --batch: take scenes k with k % N == i (i/N, 0-based)")
      ->capture_default_str()->needs(batch_opt)->configurable(false);
  night_cmd->add_option("--jobs", night_batch.jobs, "With --batch: scenes converted at once (child processes)")
      ->capture_default_str()->needs(batch_opt)->configurable(false);
  night_cmd->add_option("--scene-timeout", night_batch.scene_timeout_s,
                        "With --batch: stop a scene after this many seconds and record it failed (0: no limit)")
      ->capture_default_str()->needs(batch_opt)->configurable(false);
  night_cmd->add_option("--layout", night_batch.layout,
                        "With --batch: write each night image at its frame's path in the dataset's own layout "
                        "(manifests of solo scenes; docs/datasets.md)")
      ->needs(batch_opt)->configurable(false)->check(CLI::IsMember({"cityscapes", "kitti", "acdc"}));
  commands.push_back({night_cmd, [night_holder, batch_holder, night_cmd, argc, argv] {
    NightOptions& o = *night_holder;
    // The preset fills every knob the command line and the config file left unset.
    applyNightPreset(o.conversion, o.preset,
                     [night_cmd](const std::string& knob) { return night_cmd->count("--" + knob) > 0; });
    if (!batch_holder->list) return runNight(o);
    batch_holder->arguments.assign(argv, argv + argc);
    return runNightBatch(*batch_holder, o);
  }});
}

void addScenesCommand(CLI::App& app, std::vector<Command>& commands) {
  auto scenes_holder = std::make_shared<ScenesOptions>();
  ScenesOptions& scenes = *scenes_holder;
  CLI::App* scenes_cmd =
      app.add_subcommand("scenes", "Write a scene manifest per frame of a Cityscapes, KITTI or ACDC folder, in place "
                                   "(docs/datasets.md), and the list solo night --batch reads");
  scenes_cmd->add_option("dataset", scenes.dataset, "cityscapes, kitti or acdc")
      ->required()->check(CLI::IsMember({"cityscapes", "kitti", "acdc"}));
  scenes_cmd->add_option("root", scenes.walk.root, "The dataset's top folder")->required();
  scenes_cmd->add_option("--split", scenes.walk.split, "Only this split (train, val, ...); default: every split");
  scenes_cmd->add_option("--depth", scenes.walk.depth_folder,
                         "Folder of other depth (e.g. a monocular network's, float metres) laid out like the dataset");
  scenes_cmd->add_option("--normals", scenes.walk.normals_folder, "Folder of normals laid out like the dataset");
  scenes_cmd->add_option("-o,--output", scenes.walk.output_folder, "Folder for the manifests and scenes.txt")->required();
  commands.push_back({scenes_cmd, [scenes_holder] { return runScenes(*scenes_holder); }});
}

void addConvertCommand(CLI::App& app, std::vector<Command>& commands) {
  auto convert_holder = std::make_shared<ConvertOptions>();
  ConvertOptions& convert = *convert_holder;
  CLI::App* convert_cmd = app.add_subcommand("convert", "Convert a depth or normal map between formats");
  convert_cmd->add_option("kind", convert.kind, "depth or normals")->required()->check(CLI::IsMember({"depth", "normals"}));
  convert_cmd->add_option("input", convert.input, "Input map (PNG, EXR, TIFF, PFM, NPY)")->required();
  convert_cmd->add_option("output", convert.output, "Output map; format from the extension")->required();
  convert_cmd->add_option("--input-scale", convert.input_scale_m_per_unit, "Metres per unit of an integer depth input");
  convert_cmd->add_option("--output-scale", convert.output_scale_m_per_unit, "Metres per unit of a 16-bit PNG depth output")
      ->capture_default_str();
  commands.push_back({convert_cmd, [convert_holder] { return runConvert(*convert_holder); }});
}

void addEvalCommands(CLI::App& app, std::vector<Command>& commands) {
  auto eval_depth_holder = std::make_shared<EvalDepthOptions>();
  EvalDepthOptions& eval_depth = *eval_depth_holder;
  auto eval_normals_holder = std::make_shared<EvalNormalsOptions>();
  EvalNormalsOptions& eval_normals = *eval_normals_holder;
  auto eval_mesh_holder = std::make_shared<EvalMeshOptions>();
  EvalMeshOptions& eval_mesh = *eval_mesh_holder;
  auto eval_scene_holder = std::make_shared<EvalSceneOptions>();
  EvalSceneOptions& eval_scene = *eval_scene_holder;
  auto eval_night_holder = std::make_shared<EvalNightOptions>();
  EvalNightOptions& eval_night = *eval_night_holder;
  CLI::App* eval_cmd = app.add_subcommand(
      "eval", "Evaluate depth, normals, a mesh, a synthetic scene or night images (docs/evaluation.md)");
  eval_cmd->require_subcommand(1);
  const auto add_eval_output = [](CLI::App* cmd, EvalOutputOptions& output) {
    cmd->add_flag("--json", output.json, "Print the results as JSON on stdout instead of a table");
    cmd->add_option("--csv", output.csv, "Append one row of results to this CSV file (header when the file is new)");
  };
  CLI::App* eval_depth_cmd = eval_cmd->add_subcommand(
      "depth", "AbsRel, SqRel, RMSE, RMSElog, SILog, delta < 1.25^k of a pair, or of a dataset per image and pooled");
  eval_depth_cmd->add_option("--pred", eval_depth.prediction, "Predicted depth map, or a folder of them");
  eval_depth_cmd->add_option("--gt", eval_depth.ground_truth, "Ground-truth depth map, or a folder (matched by stem)");
  eval_depth_cmd->add_option("--list", eval_depth.list, "List file of pairs: a line PRED GT [MASK] per image");
  eval_depth_cmd->add_option("--mask", eval_depth.mask,
                             "Mask (8/16-bit or integer): non-zero pixels are evaluated; for folders, a folder by stem");
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

  CLI::App* eval_normals_cmd =
      eval_cmd->add_subcommand("normals", "Angular error of normals: mean, median, RMSE, shares");
  eval_normals_cmd->add_option("--pred", eval_normals.prediction, "Predicted normal map")->required();
  eval_normals_cmd->add_option("--gt", eval_normals.ground_truth, "Ground-truth normal map")->required();
  eval_normals_cmd->add_option("--mask", eval_normals.mask,
                               "Mask (8/16-bit or integer): non-zero pixels are evaluated");
  add_eval_output(eval_normals_cmd, eval_normals.output);

  CLI::App* eval_mesh_cmd =
      eval_cmd->add_subcommand("mesh", "Topology, defects, triangle quality, distance to a reference");
  eval_mesh_cmd->add_option("mesh", eval_mesh.mesh, "Mesh (OFF, OBJ, PLY, STL)")->required();
  eval_mesh_cmd->add_option("--ref", eval_mesh.reference, "Reference mesh for the Hausdorff and Chamfer distances");
  eval_mesh_cmd->add_option("--samples", eval_mesh.samples, "Random surface points per direction")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}));
  eval_mesh_cmd->add_option("--seed", eval_mesh.seed, "Seed of the surface sampling")->capture_default_str()->check(kSeed);
  eval_mesh_cmd->add_option("--tau", eval_mesh.tau_m,
                            "F-score distance threshold, m (default: 1 % of the reference's bounding-box diagonal)");
  add_eval_output(eval_mesh_cmd, eval_mesh.output);

  CLI::App* eval_scene_cmd = eval_cmd->add_subcommand(
      "scene", "A synthetic scene's estimated maps and outputs (refined depth, mesh) against its ground truth");
  eval_scene_cmd->add_option("scene_dir", eval_scene.scene_dir, "Scene folder (solo synth -o DIR)")->required();
  eval_scene_cmd->add_option("--refined", eval_scene.refined,
                             "Refined depth of solo depth (default: SCENE_DIR/refined.exr when present)");
  eval_scene_cmd->add_option("--mesh", eval_scene.mesh, "Mesh to evaluate (default: SCENE_DIR/mesh.ply when present)");
  eval_scene_cmd->add_option("--samples", eval_scene.samples, "Random surface points per direction (mesh distances)")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}));
  eval_scene_cmd->add_option("--seed", eval_scene.seed, "Seed of the surface sampling")->capture_default_str()->check(kSeed);
  add_eval_output(eval_scene_cmd, eval_scene.output);

  CLI::App* eval_night_cmd = eval_cmd->add_subcommand(
      "night", "Realism statistics of night images: luma, clipping, noise, colour cast, halo radius");
  eval_night_cmd->add_option("images", eval_night.images, "Images (8/16-bit sRGB PNG, JPEG, TIFF)")->required();
  eval_night_cmd->add_option("--reference", eval_night.reference,
                             "Reference set (a folder of images or a list file): its median and range, and what "
                             "falls outside it");
  add_eval_output(eval_night_cmd, eval_night.output);
  commands.push_back({eval_depth_cmd, [eval_depth_holder] { return runEvalDepth(*eval_depth_holder); }});
  commands.push_back({eval_normals_cmd, [eval_normals_holder] { return runEvalNormals(*eval_normals_holder); }});
  commands.push_back({eval_mesh_cmd, [eval_mesh_holder] { return runEvalMesh(*eval_mesh_holder); }});
  commands.push_back({eval_scene_cmd, [eval_scene_holder] { return runEvalScene(*eval_scene_holder); }});
  commands.push_back({eval_night_cmd, [eval_night_holder] { return runEvalNight(*eval_night_holder); }});
}

void addSynthCommand(CLI::App& app, std::vector<Command>& commands) {
  auto synth_holder = std::make_shared<SynthOptions>();
  SynthOptions& synth = *synth_holder;
  auto synth_size_holder = std::make_shared<std::string>("960x540");
  std::string& synth_size = *synth_size_holder;
  CLI::App* synth_cmd = app.add_subcommand("synth", "Generate a synthetic street scene with exact ground truth");
  synth_cmd->add_option("-o,--output", synth.output, "Folder to create")->required();
  synth_cmd->add_option("--seed", synth.seed, "Random seed")->capture_default_str()->check(kSeed);
  synth_cmd->add_option("--size", synth_size, "Image size WIDTHxHEIGHT in pixels")->capture_default_str();
  synth_cmd->add_option("--variant", synth.variant, "default, grazing, thin-pole, near-object, wide-sky, no-lights")
      ->capture_default_str();
  synth_cmd->add_flag("--force", synth.force, "Replace the output folder if it exists");
  synth_cmd->add_option("--day-render", synth.day_render, "Day image: raster (fast) or path (path-traced sun and sky)")
      ->capture_default_str();
  synth_cmd->add_option("--day-samples", synth.day_samples,
                        "Samples per pixel of the path-traced day image; 0 = adaptive 4 to 16")
      ->capture_default_str();
  synth_cmd->add_option("--depth-source", synth.depth_source,
                        "est/depth.exr from a simulated sensor: exact, mono, stereo or lidar (default: the half-resolution prediction)");
  commands.push_back({synth_cmd, [synth_holder, synth_size_holder] {
    parseSize(*synth_size_holder, "--size", synth_holder->width, synth_holder->height);
    return runSynth(*synth_holder);
  }});
}

void addLightsCommand(CLI::App& app, std::vector<Command>& commands) {
  auto lights_holder = std::make_shared<LightsOptions>();
  LightsOptions& lights = *lights_holder;
  CLI::App* lights_cmd = app.add_subcommand("lights", "Group and instantiate the scene's light sources (docs/lighting.md)");
  lights_cmd->add_option("scene", lights.scene, "Scene manifest (JSON); omit for the embedded default scene");
  lights_cmd->add_option("-o,--output", lights.output, "Light record to write (JSON)")->capture_default_str();
  lights_cmd->add_option("--overlay", lights.overlay, "PNG of the lights drawn on the day image");
  InstantiationOptions& instantiation = lights.stage.instantiation;
  lights_cmd->add_option("--seed", instantiation.seed, "Random seed")->capture_default_str()->check(kSeed);
  lights_cmd->add_flag("--ablation", instantiation.ablation, "Every light on, white, one strength (the paper's ablation)");
  lights_cmd->add_option("--ablation-luminance", instantiation.ablation_luminance_cd_m2, "The ablation's strength, cd/m^2")
      ->capture_default_str();
  lights_cmd->add_option("--table", lights.stage.illuminant_table, "Illuminant table CSV (default: the bundled one)");
  lights_cmd->add_option("--from", lights.from_record, "Read an (edited) light record instead of sampling");
  lights_cmd->add_option("--report", lights.report, "Report JSON to write");
  commands.push_back({lights_cmd, [lights_holder] { return runLights(*lights_holder); }});
}

void addProposeLightsCommand(CLI::App& app, std::vector<Command>& commands) {
  auto holder = std::make_shared<ProposeLightsOptions>();
  ProposeLightsOptions& propose = *holder;
  CLI::App* cmd = app.add_subcommand("propose-lights", "Propose lights for scenes without a light map (docs/lighting.md)");
  cmd->add_option("scenes", propose.scenes, "Scene manifests (JSON)")->required();
  cmd->add_option("-o,--output", propose.output, "Folder to write lights.png, light_groups.png, proposals.json")->required();
  cmd->add_option("--overlay", propose.overlay, "PNG of the proposals drawn on the day image");
  cmd->add_flag("--evaluate", propose.evaluate, "Score against the scenes' exact light maps (solo synth scenes)");
  cmd->add_option("--min-true-pixels", propose.min_true_pixels, "Evaluation: ignore true lights smaller than this")
      ->capture_default_str()->check(CLI::Range(0, 1000000));
  commands.push_back({cmd, [holder] { return runProposeLights(*holder); }});
}

void addIlluminantCommands(CLI::App& app, std::vector<Command>& commands) {
  auto illuminant_add_holder = std::make_shared<IlluminantAddOptions>();
  IlluminantAddOptions& illuminant_add = *illuminant_add_holder;
  auto illuminant_regenerate_holder = std::make_shared<IlluminantRegenerateOptions>();
  IlluminantRegenerateOptions& illuminant_regenerate = *illuminant_regenerate_holder;
  CLI::App* illuminant_cmd = app.add_subcommand("illuminant", "Build or extend a night-illuminant table");
  illuminant_cmd->require_subcommand(1);
  CLI::App* illuminant_add_cmd =
      illuminant_cmd->add_subcommand("add", "Add a chromaticity sample from a spectrum, a CCT or a gray-card raw photo");
  illuminant_add_cmd->add_option("table", illuminant_add.table, "Table CSV (created when absent)")->required();
  illuminant_add_cmd->add_option("--category", illuminant_add.category, "Light category, e.g. street_light_LT")->required();
  illuminant_add_cmd->add_option("--spectrum", illuminant_add.spectrum, "Spectrum CSV: wavelength_nm,relative_power");
  illuminant_add_cmd->add_option("--cct", illuminant_add.cct_K, "Planckian colour temperature in kelvin");
  illuminant_add_cmd->add_option("--raw", illuminant_add.raw, "Raw photo (DNG) of a gray card lit by the light");
  illuminant_add_cmd->add_option("--roi", illuminant_add.roi, "Gray card region X,Y,WIDTH,HEIGHT in the raw photo");
  illuminant_add_cmd->add_option("--source", illuminant_add.source, "Provenance text (lamp, place, date)");
  CLI::App* illuminant_regenerate_cmd =
      illuminant_cmd->add_subcommand("regenerate", "Rebuild the bundled table from its recipe (reproducibility)");
  illuminant_regenerate_cmd->add_option("-o,--output", illuminant_regenerate.output, "Table CSV to write")->required();
  illuminant_regenerate_cmd->add_option("--recipe", illuminant_regenerate.recipe, "Recipe CSV (default: bundled)");
  illuminant_regenerate_cmd->add_option("--regions", illuminant_regenerate.regions, "Chromaticity regions CSV");
  commands.push_back({illuminant_add_cmd, [illuminant_add_holder] { return runIlluminantAdd(*illuminant_add_holder); }});
  commands.push_back({illuminant_regenerate_cmd,
                      [illuminant_regenerate_holder] { return runIlluminantRegenerate(*illuminant_regenerate_holder); }});
}

void addMeshCommands(CLI::App& app, std::vector<Command>& commands) {
  auto mesh_from_depth_holder = std::make_shared<MeshFromDepthOptions>();
  MeshFromDepthOptions& mesh_from_depth = *mesh_from_depth_holder;
  auto mesh_clean_holder = std::make_shared<MeshCleanOptions>();
  MeshCleanOptions& mesh_clean = *mesh_clean_holder;
  CLI::App* mesh_cmd = app.add_subcommand("mesh", "Mesh from depth, mesh repair and hole filling (docs/mesh.md)");
  mesh_cmd->require_subcommand(1);
  CLI::App* mesh_from_depth_cmd = mesh_cmd->add_subcommand(
      "from-depth", "Backproject a scene's depth, remove spurious faces, fill holes, close foreground solids");
  mesh_from_depth_cmd->add_option("scene", mesh_from_depth.scene, "Scene manifest (JSON)")->required();
  mesh_from_depth_cmd->add_option("-o,--output", mesh_from_depth.output, "Mesh to write (PLY, OBJ, OFF, STL)")->required();
  mesh_from_depth_cmd->add_option("--report", mesh_from_depth.report, "Report JSON to write");
  mesh_from_depth_cmd->add_option("--uncertain", mesh_from_depth.uncertain, "Uncertain mask (non-zero = uncertain)");
  mesh_from_depth_cmd->add_option("--truth", mesh_from_depth.truth,
                                  "Ground-truth scene (depth and normals): score the spurious-face removal");
  mesh_from_depth_cmd->add_flag("!--no-solids", mesh_from_depth.cleanup.close_solids, "Leave foreground things as open sheets");
  mesh_from_depth_cmd->add_flag("!--no-backdrops", mesh_from_depth.cleanup.backdrops,
                                "Leave open the frame holes only a backdrop behind the occluders closes");
  mesh_from_depth_cmd->add_flag("!--no-evaluation", mesh_from_depth.cleanup.evaluate,
                                "Skip the final topology and self-intersection counts");
  CLI::App* mesh_clean_cmd =
      mesh_cmd->add_subcommand("clean", "Repair a triangle mesh, fill its holes, remove self-intersections or wrap it");
  mesh_clean_cmd->add_option("input", mesh_clean.input, "Mesh to read (PLY, OBJ, OFF, STL)")->required();
  mesh_clean_cmd->add_option("-o,--output", mesh_clean.output, "Mesh to write")->required();
  mesh_clean_cmd->add_option("--report", mesh_clean.report, "Report JSON to write");
  const CLI::Validator positive_finite(
      [](std::string& text) {
        double value = 0;
        try {
          value = std::stod(text);
        } catch (const std::exception&) {
          return std::string("not a number: ") + text;
        }
        return std::isfinite(value) && value > 0 ? std::string() : "must be finite and > 0: " + text;
      },
      "POSITIVE");
  mesh_clean_cmd->add_flag("!--no-repair-intersections", mesh_clean.cleanup.repair_intersections,
                           "Leave self-intersections as they are (reported)");
  mesh_clean_cmd->add_option("--repair-time-limit", mesh_clean.cleanup.intersection_repair.time_limit_s,
                             "Seconds the self-intersection repair may take")
      ->capture_default_str()->check(positive_finite);
  mesh_clean_cmd->add_flag("--wrap", mesh_clean.cleanup.wrap, "Output the alpha wrap (closed by construction)");
  mesh_clean_cmd->add_flag("!--no-wrap-fallback", mesh_clean.cleanup.wrap_fallback,
                           "Do not wrap when the repair leaves the mesh not closed");
  mesh_clean_cmd->add_option("--wrap-alpha", mesh_clean.cleanup.wrapping.alpha_fraction,
                             "Wrap alpha, fraction of the bounding-box diagonal")
      ->capture_default_str()->check(positive_finite);
  mesh_clean_cmd->add_option("--wrap-offset", mesh_clean.cleanup.wrapping.offset_fraction,
                             "Wrap offset, fraction of the bounding-box diagonal")
      ->capture_default_str()->check(positive_finite);
  mesh_clean_cmd->add_option("--wrap-time-limit", mesh_clean.cleanup.wrapping.time_limit_s,
                             "Seconds the alpha wrap may take")
      ->capture_default_str()->check(positive_finite);
  commands.push_back({mesh_from_depth_cmd, [mesh_from_depth_holder] { return runMeshFromDepth(*mesh_from_depth_holder); }});
  commands.push_back({mesh_clean_cmd, [mesh_clean_holder] { return runMeshClean(*mesh_clean_holder); }});
}

// The camera on the post-process options: the one --shutter or --f-number made, or a new one.
CameraExposure& postCamera(PostProcessOptions& post) {
  std::optional<CameraExposure>& camera = post.exposure_options.camera;
  if (!camera) camera.emplace();
  return *camera;
}

// solo post's glare, exposure and noise flags.
void addPostCameraFlags(CLI::App* post_cmd, PostProcessOptions& post) {
  CLI::Option* post_stops = post_cmd->add_option("--stops", post.exposure_options.stops, "Exposure in stops")->capture_default_str();
  post_cmd->add_option_function<double>(
              "--shutter", [&post](const double& shutter_s) { postCamera(post).shutter_s = shutter_s; },
              "Camera shutter time, s (camera: ISO 3200, 1/30 s, f/2 = +3.25 stops)")
      ->excludes(post_stops);
  post_cmd->add_option_function<double>(
              "--f-number", [&post](const double& f_number) { postCamera(post).f_number = f_number; },
              "Camera f-number (with --shutter and --iso)")
      ->excludes(post_stops);
  post_cmd->add_option("--iso", post.noise_options.iso, "Sensor ISO (noise calibration 100 to 3200; the camera's ISO)")
      ->capture_default_str();
  post_cmd->add_flag("!--no-glare", post.glare, "Skip the fog glare");
  post_cmd->add_option("--glare-threshold", post.glare_options.threshold,
                       "Luminance above which pixels glow (render units before exposure); -1 = what clips; the "
                       "reference uses 0")
      ->capture_default_str();
  post_cmd->add_option("--glare-size", post.glare_options.size, "Glare kernel size 2^N px")->capture_default_str();
  namedChoice(post_cmd->add_option("--glare-method", post.glare_options.method, "auto, direct, fft or tiled"),
              kGlareMethods, post.glare_options.method);
  post_cmd->add_flag("!--no-noise", post.noise, "Skip the sensor noise");
  post_cmd->add_option("--noise-scale", post.noise_options.std_scale, "Noise standard deviation multiplier")->capture_default_str();
  post_cmd->add_flag("!--no-demosaic", post.noise_options.demosaic, "Noise without the RGGB mosaic: every pixel samples R, G, B");
  post_cmd->add_option("--chroma-denoise", post.noise_options.chroma_denoise_sigma_px,
                       "Chroma noise reduction: Gaussian sigma in px on the noise's colour differences, linear "
                       "and after the curve; 0 = off")
      ->capture_default_str();
  post_cmd->add_option("--chroma-denoise-strength", post.noise_options.chroma_denoise_strength,
                       "Share of the chroma noise replaced by its smoothed version, 0 to 1")
      ->capture_default_str();
  post_cmd->add_option("--seed", post.noise_options.seed, "Noise seed")->capture_default_str()->check(kSeed);
}

// solo post's colour flags, then the glare scatter (last in --help).
void addPostColourFlags(CLI::App* post_cmd, PostProcessOptions& post) {
  ColourEncodingOptions& encoding = post.encoding_options;
  post_cmd->add_flag("!--no-adaptation", post.adaptation, "Skip the Bradford E to D65 adaptation");
  namedChoice(post_cmd->add_option("--curve", encoding.curve, "gamma2.2, srgb or linear"), kTransferCurves, encoding.curve);
  namedChoice(post_cmd->add_option("--negatives", encoding.negatives, "Out-of-gamut colours: desaturate or clip"),
              kNegativeHandlings, encoding.negatives);
  namedChoice(post_cmd->add_option("--highlights", encoding.highlights,
                                   "Colours above white: desaturate (toward white, hue kept) or clip"),
              kHighlightHandlings, encoding.highlights);
  post_cmd->add_option("--highlight-knee", encoding.highlight_knee,
                       "Desaturation starts above this share of a colour's headroom, 0 to 1 (1 = hard)")
      ->capture_default_str();
  post_cmd->add_option("--white-clip", encoding.white_clip,
                       "Video knee: linear level encoded as full white, in sensor whites (1 = clip at white)")
      ->capture_default_str();
  post_cmd->add_option("--knee-point", encoding.knee_point, "Video knee: encoded luminance where it starts, 0 to 1")
      ->capture_default_str();
  post_cmd->add_option("--glare-scatter", post.glare_options.scatter_fraction,
                       "Share of a bright pixel's excess the glow carries (1 = the reference)")
      ->capture_default_str();
}

void addPostCommand(CLI::App& app, std::vector<Command>& commands) {
  auto post_holder = std::make_shared<PostOptions>();
  PostOptions& post = *post_holder;
  CLI::App* post_cmd =
      app.add_subcommand("post", "Post-process a linear XYZ render: glare, exposure, noise, colour (docs/post-processing.md)");
  post_cmd->add_option("input", post.input, "Linear XYZ image relative to white E (EXR, TIFF, PFM, NPY)")->required();
  post_cmd->add_option("-o,--output", post.output, "Image to write: .png/.tif (8-bit), .jpg, .exr (linear sRGB)")
      ->capture_default_str();
  post_cmd->add_option("--report", post.report, "Report JSON to write");
  post_cmd->add_flag("--16bit", post.sixteen_bit, "16-bit PNG or TIFF");
  addPostCameraFlags(post_cmd, post.post);
  addPostColourFlags(post_cmd, post.post);
  commands.push_back({post_cmd, [post_holder] { return runPost(*post_holder); }});
}

void addFdaCommand(CLI::App& app, std::vector<Command>& commands) {
  auto fda_holder = std::make_shared<FdaCommandOptions>();
  FdaCommandOptions& fda = *fda_holder;
  CLI::App* fda_cmd = app.add_subcommand("fda", "Fourier domain adaptation of a day photo toward a night photo (baseline)");
  fda_cmd->add_option("--source", fda.source, "Day image (its content and phase are kept)")->required();
  fda_cmd->add_option("--target", fda.target, "Night image (its low-frequency amplitudes are taken)")->required();
  fda_cmd->add_option("-o,--output", fda.output, "Image to write (.png, .tif, .jpg; .exr unclamped)")->required();
  fda_cmd->add_option("--beta", fda.beta, "Band half-size as a fraction of min(H, W)")->capture_default_str();
  fda_cmd->add_flag("--16bit", fda.sixteen_bit, "16-bit PNG or TIFF");
  fda_cmd->add_option("--report", fda.report, "Report JSON to write");
  commands.push_back({fda_cmd, [fda_holder] { return runFda(*fda_holder); }});
}

void addDepthCommand(CLI::App& app, std::vector<Command>& commands) {
  auto depth_holder = std::make_shared<DepthOptions>();
  DepthOptions& depth = *depth_holder;
  CLI::App* depth_cmd = app.add_subcommand("depth", "Refine a scene's depth: upsample, filter, uncertain regions, optimise");
  depth_cmd->add_option("scene", depth.scene, "Scene manifest (JSON)")->required();
  depth_cmd->add_option("-o,--output", depth.output, "Refined depth to write (EXR, TIFF, PFM, NPY, PNG)")->capture_default_str();
  depth_cmd->add_option("--report", depth.report, "Report JSON to write (default: <output>.report.json)");
  DepthRefinementOptions& refinement = depth.refinement;
  namedChoice(depth_cmd->add_option("--optimizer", refinement.optimizer, "ceres, or adam (the paper's optimiser)"),
              kDepthOptimizers, refinement.optimizer, "{ceres,adam}");
  // The objective first: the tangent model below applies to whichever is chosen.
  depth_cmd
      ->add_option_function<std::string>(
          "--objective",
          [&refinement](const std::string& name) {
            refinement.optimization.objective =
                name == "paper" ? NormalGuidedObjectiveOptions::paper() : NormalGuidedObjectiveOptions{};
          },
          "default (one-sided differences, data term in footprints, Cauchy loss) or paper (docs/depth-refinement.md)")
      ->check(CLI::IsMember({"default", "paper"}))
      ->default_str("default");
  // One tangent model for both optimisers' objectives.
  namedChoice(depth_cmd->add_option_function<TangentModel>(
                  "--tangent-model",
                  [&refinement](const TangentModel& model) {
                    refinement.optimization.objective.tangent_model = model;
                    refinement.adam.objective.tangent_model = model;
                  },
                  "perspective (exact pinhole tangents) or paper"),
              kTangentModels, refinement.optimization.objective.tangent_model, "{perspective,paper}");
  depth_cmd->add_flag("!--no-upsample", refinement.upsampling.enabled, "Resize maps by nearest neighbour instead of upsampling");
  depth_cmd->add_flag("!--no-complete", refinement.complete, "Skip the depth completion (holes stay holes)");
  depth_cmd->add_flag("!--no-filter", refinement.filter, "Skip the instance-reference cross-bilateral filter");
  depth_cmd->add_flag("!--no-uncertain", refinement.uncertain_regions, "Skip the uncertain regions");
  depth_cmd->add_flag("!--no-optimize", refinement.optimize, "Skip the normal-guided optimisation");
  commands.push_back({depth_cmd, [depth_holder] { return runDepth(*depth_holder); }});
}

void addBenchCommands(CLI::App& app, std::vector<Command>& commands) {
  auto bench_accuracy_holder = std::make_shared<BenchAccuracyOptions>();
  BenchAccuracyOptions& bench_accuracy = *bench_accuracy_holder;
  auto bench_size_holder = std::make_shared<std::string>("960x540");
  std::string& bench_size = *bench_size_holder;
  auto bench_realism_holder = std::make_shared<BenchRealismOptions>();
  BenchRealismOptions& bench_realism = *bench_realism_holder;
  auto realism_size_holder = std::make_shared<std::string>("960x540");
  std::string& realism_size = *realism_size_holder;
  CLI::App* bench_cmd = app.add_subcommand("bench", "Measurements on synthetic scenes (docs/accuracy.md)");
  bench_cmd->require_subcommand(1);
  CLI::App* bench_accuracy_cmd = bench_cmd->add_subcommand(
      "accuracy", "Sweep the knobs that trade accuracy for time against ground truth: CSV and plots per stage");
  bench_accuracy_cmd->add_option("-o,--output", bench_accuracy.output, "Folder to write (CSV, .gp, PNG, README)")
      ->required();
  CLI::Option* bench_scene = bench_accuracy_cmd->add_option(
      "--scene", bench_accuracy.scene, "A solo synth folder (or its scene.json) instead of making one");
  bench_accuracy_cmd->add_option("--scene-size", bench_size, "Size WIDTHxHEIGHT of the scene made")
      ->capture_default_str()
      ->excludes(bench_scene);
  bench_accuracy_cmd->add_option("--seed", bench_accuracy.seed, "Seed: scene made, lights, renders")
      ->capture_default_str()->check(kSeed);
  bench_accuracy_cmd->add_flag("--quick", bench_accuracy.quick, "Fewer points, smaller samples");
  bench_accuracy_cmd->add_option("--stages", bench_accuracy.stages, "Sweeps to run: refine,mesh,render,end_to_end")
      ->delimiter(',')
      ->capture_default_str();
  bench_accuracy_cmd->add_option("--reference-spp", bench_accuracy.reference_spp,
                                 "Samples per pixel of the converged references (0: 256, 64 with --quick)")
      ->capture_default_str();
  bench_accuracy_cmd->add_option("--repeats", bench_accuracy.repeats, "Timing runs of a cheap point (median)")
      ->capture_default_str();
  bench_accuracy_cmd->add_flag("!--no-plots", bench_accuracy.plots, "Write no gnuplot script and run no gnuplot");

  CLI::App* bench_realism_cmd = bench_cmd->add_subcommand(
      "realism",
      "solo night on the default scene and synthetic streets: realism statistics against the targets, "
      "times, contact sheet (docs/realism.md)");
  bench_realism_cmd->add_option("-o,--output", bench_realism.output, "Folder to write (CSV, README, PNG)")->required();
  bench_realism_cmd->add_option("--seed", bench_realism.seed, "Seed of every night run")->capture_default_str()->check(kSeed);
  bench_realism_cmd->add_flag("--quick", bench_realism.quick, "The default scene and two streets only");
  bench_realism_cmd->add_option("--preset", bench_realism.preset, "solo night preset: draft, default or final")
      ->capture_default_str()
      ->check(CLI::IsMember(nightPresetNames()));
  bench_realism_cmd->add_option("--size", realism_size, "Size WIDTHxHEIGHT of the streets (one is twice that)")
      ->capture_default_str();
  commands.push_back({bench_accuracy_cmd, [bench_accuracy_holder, bench_size_holder] {
    parseSize(*bench_size_holder, "--scene-size", bench_accuracy_holder->width, bench_accuracy_holder->height);
    return runBenchAccuracy(*bench_accuracy_holder);
  }});
  commands.push_back({bench_realism_cmd, [bench_realism_holder, realism_size_holder] {
    parseSize(*realism_size_holder, "--size", bench_realism_holder->width, bench_realism_holder->height);
    return runBenchRealism(*bench_realism_holder);
  }});
}

}  // namespace

int main(int argc, char** argv) {
  // SIGINT, SIGTERM, SIGHUP remove the hidden temporaries being written; a batch's scene also
  // stops when the batch process dies.
  solo::removeTemporariesOnSignals();
  solo::stopWithBatchParent();
  keepFreedLargeBuffersForReuse();
  CLI::App app{"solo: turns a daytime street photo into a physically based night image"};
  app.require_subcommand(1);
  app.set_version_flag("--version", [] { return versionText(); }, "Print solo's version and its libraries' versions");
  std::vector<Command> commands;
  addInfoCommand(app, commands);
  addNightCommand(app, commands, argc, argv);
  addScenesCommand(app, commands);
  addConvertCommand(app, commands);
  addEvalCommands(app, commands);
  addSynthCommand(app, commands);
  addLightsCommand(app, commands);
  addProposeLightsCommand(app, commands);
  addIlluminantCommands(app, commands);
  addMeshCommands(app, commands);
  addPostCommand(app, commands);
  addFdaCommand(app, commands);
  addDepthCommand(app, commands);
  addBenchCommands(app, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 does not name the config file in its errors: say which file it was.
    const CLI::Option* config = app.get_config_ptr();
    if (config && config->count() > 0 &&
        (dynamic_cast<const CLI::ConfigError*>(&e) || dynamic_cast<const CLI::FileError*>(&e))) {
      const std::string file = config->as<std::string>();
      std::string problem = e.what();
      const std::string extra = "INI was not able to parse ";
      if (problem.rfind(extra, 0) == 0) problem = "unknown key or malformed line \"" + problem.substr(extra.size()) + "\"";
      std::cerr << "solo: error: " << file << ": " << problem << " (config file; docs/presets.md)\n";
      return 2;
    }
    if (config && config->count() > 0 &&
        (dynamic_cast<const CLI::ConversionError*>(&e) || dynamic_cast<const CLI::ArgumentMismatch*>(&e))) {
      std::cerr << "solo: error: " << e.what() << " (on the command line or in the config file "
                << config->as<std::string>() << ")\n";
      return 2;
    }
    // Help and --version exit 0; every other command-line error is bad input, exit 2 like the
    // errors the commands raise.
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (const Command& command : commands)
      if (command.cli->parsed()) return command.run();
  } catch (const solo::InputError& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the run was given (or derived) cannot be used: bad input, named.
    std::cerr << "solo: error: " << (e.path1().empty() ? std::string() : e.path1().string() + ": ")
              << e.code().message() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "solo: error: out of memory (the scene or an option asked for more than this machine has)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 1;
  }
  return 1;
}
