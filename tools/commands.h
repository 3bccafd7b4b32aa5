#pragma once
// The solo subcommands. Each takes an options struct that maps one to one onto its
// command-line flags (main.cpp is the only file that knows CLI11) and returns an exit code.

#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/lighting/light_proposals.h>
#include <solo/lighting/light_stage.h>
#include <solo/pipeline/data_dir.h>
#include <solo/pipeline/dataset_scenes.h>
#include <solo/pipeline/evaluation.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_evaluation.h>
#include <solo/pipeline/night_job.h>
#include <solo/pipeline/realism_bench.h>
#include <solo/post/post_process.h>
#include <solo/synth/scene_folder.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace solo::tools {

/// Libraries solo was built against, name -> version (compile-time): the pipeline's and CLI11.
std::vector<std::pair<std::string, std::string>> dependencyVersions();

/// `solo --version`: solo's version and dependencyVersions().
std::string versionText();

struct InfoOptions {
  std::filesystem::path scene;
  bool json = false;
};
int runInfo(const InfoOptions& options);

/// `solo night`: the job's files and the conversion's settings, each flag bound straight onto
/// a field of the library's option structs (pipeline/night_job.h, night_conversion.h).
struct NightOptions {
  NightJobOptions job;
  NightConversionOptions conversion;
  /// Quality preset (draft, default, final; night_presets.h). main.cpp applies it to every
  /// knob not given on the command line or in the config file.
  std::string preset = "default";
  std::optional<std::filesystem::path> write_config;  ///< the effective configuration (TOML)
  bool verbose = false;  ///< every stage's notes on the terminal (the report has them always)
};
int runNight(const NightOptions& options);
/// The night options as a config file `solo --config FILE night` (or `solo night --config
/// FILE`) reads back to the same options: TOML, one `key = value` per option under `[night]`,
/// keys the long option names without dashes. Unset optional paths and write_config are left
/// out. Throws InputError for a path holding both quote characters (TOML strings cannot hold it).
std::string nightConfigText(const NightOptions& options);

/// `solo night --batch`: every scene of a list or folder, each in a child process (docs/batch.md;
/// the library's solo::runNightBatch, pipeline/night_batch.h). The NightOptions give the output
/// folder (output), the batch seed, the contact sheet switch and a scene (refused).
struct NightBatchOptions {
  std::optional<std::filesystem::path> list;  ///< list file of manifests, or a folder searched for them
  std::string shard = "0/1";                  ///< i/N: scenes k with k % N == i
  int jobs = 1;                               ///< scenes converted at once
  double scene_timeout_s = 0;                 ///< a scene running longer is stopped and recorded failed; 0: none
  std::string layout;                         ///< "cityscapes", "kitti", "acdc": night images in that layout; empty: flat
  std::vector<std::string> arguments;         ///< the command line, forwarded to the scenes minus the batch's own
};
int runNightBatch(const NightBatchOptions& batch, const NightOptions& night);

/// `solo scenes cityscapes|kitti|acdc ROOT -o DIR`: a manifest per frame of a dataset, in place,
/// and the list the batch reads (pipeline/dataset_scenes.h, docs/datasets.md).
struct ScenesOptions {
  std::string dataset;  ///< "cityscapes", "kitti" or "acdc"
  DatasetScenesOptions walk;
};
int runScenes(const ScenesOptions& options);

struct ConvertOptions {
  std::string kind = "depth";  ///< "depth" or "normals"
  std::filesystem::path input, output;
  double input_scale_m_per_unit = 0;    ///< for integer depth inputs
  double output_scale_m_per_unit = 1.0 / 256.0;  ///< for 16-bit PNG depth outputs
};
int runConvert(const ConvertOptions& options);

/// `solo eval ...`: where the results go besides (or instead of) the terminal table.
struct EvalOutputOptions {
  bool json = false;                       ///< print JSON on stdout instead of the table
  std::optional<std::filesystem::path> csv;  ///< append one row (header when the file is new)
};

/// `solo eval depth|normals|mesh|scene|night`: the library's evaluation (pipeline/evaluation.h,
/// night_evaluation.h), each flag bound onto a field of its options, and where the result goes.
struct EvalDepthOptions : DepthFilesEvaluationOptions {
  EvalOutputOptions output;
};
int runEvalDepth(const EvalDepthOptions& options);

struct EvalNormalsOptions : NormalFilesEvaluationOptions {
  EvalOutputOptions output;
};
int runEvalNormals(const EvalNormalsOptions& options);

struct EvalMeshOptions : MeshFileEvaluationOptions {
  EvalOutputOptions output;
};
int runEvalMesh(const EvalMeshOptions& options);

/// `solo eval scene`: a synthetic scene folder's estimated maps and the outputs written into it
/// (refined depth, mesh) against its ground truth (docs/evaluation.md).
struct EvalSceneOptions : SceneFolderEvaluationOptions {
  EvalOutputOptions output;
};
int runEvalScene(const EvalSceneOptions& options);

/// `solo eval night`: the realism statistics of night images (docs/evaluation.md), and with a
/// reference set its median and range per statistic and what falls outside it.
struct EvalNightOptions : NightEvaluationOptions {
  EvalOutputOptions output;
};
int runEvalNight(const EvalNightOptions& options);

/// `solo synth`: the library's scene-folder options (synth/scene_folder.h) and the folder.
struct SynthOptions : SyntheticSceneOptions {
  std::filesystem::path output;  ///< folder to create
};
int runSynth(const SynthOptions& options);

/// `solo depth`: the depth refinement stage alone (docs/depth-refinement.md). Writes the
/// refined depth, its normals (<output stem>.normals.<ext>) and the uncertain mask
/// (<output stem>.uncertain.png) next to it.
struct DepthOptions {
  std::filesystem::path scene;
  std::filesystem::path output = "refined.exr";
  std::optional<std::filesystem::path> report;  ///< none: <output stem>.report.json
  /// The stage's options, each flag bound onto a field; --tangent-model sets the objective of
  /// both optimisers (optimization and adam).
  DepthRefinementOptions refinement;
};
int runDepth(const DepthOptions& options);

/// `solo mesh from-depth`: the mesh stage's options (geometry/mesh_cleanup.h), each flag bound
/// onto a field, and the files.
struct MeshFromDepthOptions {
  std::filesystem::path scene;   ///< scene manifest
  std::filesystem::path output;  ///< mesh file: PLY, OBJ, OFF or STL by extension
  std::optional<std::filesystem::path> report;     ///< report JSON
  std::optional<std::filesystem::path> uncertain;  ///< uncertain mask (8/16-bit, non-zero = uncertain)
  std::optional<std::filesystem::path> truth;      ///< ground-truth scene: score the spurious-face removal
  DepthMeshCleanupOptions cleanup;
};
int runMeshFromDepth(const MeshFromDepthOptions& options);

struct MeshCleanOptions {
  std::filesystem::path input, output;          ///< PLY, OBJ, OFF or STL
  std::optional<std::filesystem::path> report;  ///< report JSON
  MeshCleanupOptions cleanup;                   ///< the repair (no flags: the library's defaults)
};
int runMeshClean(const MeshCleanOptions& options);

/// `solo lights`: the light stage's options (lighting/light_stage.h), each flag bound onto a
/// field, and the files.
struct LightsOptions {
  std::optional<std::filesystem::path> scene;  ///< none: the embedded default scene
  std::filesystem::path output = "lights.json";  ///< the light record
  std::optional<std::filesystem::path> overlay;  ///< PNG of the lights on the day image
  std::optional<std::filesystem::path> report;   ///< run report JSON
  std::optional<std::filesystem::path> from_record;  ///< an edited record to validate and redraw
  LightStageOptions stage;  ///< an empty illuminant_table is the bundled table (data_dir.h)
};
int runLights(const LightsOptions& options);

/// `solo propose-lights`: lights for scenes without a light map (lighting/light_proposals.h).
/// One scene writes lights.png, light_groups.png and proposals.json into `output`; several scenes
/// one subfolder each, named after the scene's folder.
struct ProposeLightsOptions {
  std::vector<std::filesystem::path> scenes;
  std::filesystem::path output;
  std::optional<std::filesystem::path> overlay;  ///< the proposals drawn on the day image (file name in each folder)
  bool evaluate = false;     ///< score against the scenes' exact light maps (`solo synth` scenes)
  int min_true_pixels = 30;  ///< true lights smaller than this are ignored in the evaluation
  LightProposalOptions proposals;
};
int runProposeLights(const ProposeLightsOptions& options);

struct IlluminantAddOptions {
  std::filesystem::path table;  ///< CSV to append to (created when absent)
  std::string category;         ///< light category name
  std::optional<std::filesystem::path> spectrum;  ///< wavelength_nm,relative_power CSV
  std::optional<double> cct_K;                    ///< Planckian colour temperature, kelvin
  std::optional<std::filesystem::path> raw;       ///< raw photo (DNG) of a gray card
  std::optional<std::string> roi;                 ///< X,Y,WIDTH,HEIGHT of the card in the raw photo
  std::string source;                             ///< free provenance text
};
int runIlluminantAdd(const IlluminantAddOptions& options);

struct IlluminantRegenerateOptions {
  std::optional<std::filesystem::path> recipe;   ///< default: data/illuminants/recipe.csv
  std::optional<std::filesystem::path> regions;  ///< default: beside the recipe
  std::filesystem::path output;
};
int runIlluminantRegenerate(const IlluminantRegenerateOptions& options);

/// `solo post`: the post-process on a linear XYZ image (white point E), docs/post-processing.md.
struct PostOptions {
  std::filesystem::path input;                  ///< EXR/TIFF/PFM/NPY, 3 channels X, Y, Z (or R, G, B holding them)
  std::filesystem::path output = "night.png";   ///< .png/.tif (8-bit, 16 with sixteen_bit), .jpg, .exr (linear)
  std::optional<std::filesystem::path> report;  ///< run report JSON
  bool sixteen_bit = false;
  /// The post-process, each flag bound onto a field. --shutter and --f-number set
  /// exposure_options.camera; its ISO is --iso, noise_options.iso (runPost copies it).
  PostProcessOptions post;
};
int runPost(const PostOptions& options);

/// `solo fda`: Fourier domain adaptation of a day photo toward a night photo.
struct FdaCommandOptions {
  std::filesystem::path source, target, output;
  double beta = 0.01;
  bool sixteen_bit = false;
  std::optional<std::filesystem::path> report;
};
int runFda(const FdaCommandOptions& options);

/// `solo bench accuracy`: sweeps of the knobs that trade accuracy for time on a synthetic scene
/// with exact ground truth; CSV per stage, gnuplot plots and a README in `output`
/// (docs/accuracy.md).
struct BenchAccuracyOptions {
  std::filesystem::path output;                ///< folder to write (created)
  std::optional<std::filesystem::path> scene;  ///< a `solo synth` folder or its scene.json; none: made in output/scene
  int width = 960, height = 540;               ///< pixels, of the scene made
  std::uint64_t seed = 1;                      ///< the scene made, lights, renders, surface sampling
  bool quick = false;                          ///< fewer points (tests, a first look)
  std::vector<std::string> stages = {"refine", "mesh", "render", "end_to_end"};
  int reference_spp = 0;  ///< samples per pixel of the converged references; 0: 256 (64 with quick)
  int repeats = 3;        ///< timing runs of a cheap point (median)
  bool plots = true;      ///< write gnuplot scripts and run gnuplot when it is on PATH
};
int runBenchAccuracy(const BenchAccuracyOptions& options);

/// `solo bench realism`: the library's realism benchmark (pipeline/realism_bench.h), each flag
/// bound onto a field of its options; prints a line per scene and the table.
using BenchRealismOptions = RealismBenchOptions;
int runBenchRealism(const BenchRealismOptions& options);

}  // namespace solo::tools
