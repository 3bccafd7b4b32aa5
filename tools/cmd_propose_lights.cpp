// `solo propose-lights`: lights for scenes without a light map (lighting/light_proposals.h),
// and with --evaluate their accuracy against the scenes' exact light maps.

#include "commands.h"

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/scene.h>

#include <cstdio>
#include <iostream>

namespace fs = std::filesystem;

namespace solo::tools {
namespace {

cv::Mat asUint16(const cv::Mat& ids) {
  cv::Mat out;
  ids.convertTo(out, CV_16U);
  return out;
}

// The exact z-depth of a synthetic scene (its ground-truth manifest's depth) at the image size.
cv::Mat trueDepth(const fs::path& scene_file, const Scene& scene) {
  const Scene truth = loadScene(groundTruthManifest(scene_file));
  if (truth.depth_m.size() != scene.image.size())
    throw InputError(scene_file, "the ground truth's depth is " + sizeText(truth.depth_m) + ", the image " +
                                     sizeText(scene.image));
  return truth.depth_m;
}

// Proposes for one scene, writes its files into `folder`; adds its evaluation when asked.
void proposeOne(const fs::path& scene_file, const fs::path& folder, const ProposeLightsOptions& options,
                ProposalEvaluation* total) {
  const Scene scene = loadScene(scene_file);
  const LightProposalResult result = proposeLights(scene, options.proposals);
  fs::create_directories(folder);
  writeImage(folder / "lights.png", asUint16(result.lights));
  writeImage(folder / "light_groups.png", asUint16(result.light_groups));
  writeTextAtomically(folder / "proposals.json", lightProposalsJson(result, scene_file.string()));
  if (options.overlay) writeImage(folder / options.overlay->filename(), drawLightProposals(scene.image, result));
  std::printf("%s: %zu lights proposed in %.3f s\n", scene_file.string().c_str(), result.proposals.size(),
              result.total_seconds);
  if (!total) return;
  if (scene.lights.empty()) throw InputError(scene_file, "--evaluate needs the scene's exact light map (\"lights\")");
  ProposalEvaluationOptions evaluation_options;
  evaluation_options.min_true_pixels = options.min_true_pixels;
  const ProposalEvaluation evaluation =
      evaluateLightProposals(result, resampleLabels(scene.lights, scene.image.size()), trueDepth(scene_file, scene),
                             scene.camera, evaluation_options);
  writeTextAtomically(folder / "evaluation.md",
                      proposalEvaluationTable(evaluation) + "\nMisses:\n\n```\n" + proposalMissesText(evaluation) + "```\n");
  for (int f = 0; f < kLightFamilyCount; ++f)
    total->families[static_cast<std::size_t>(f)].add(evaluation.families[static_cast<std::size_t>(f)]);
}

}  // namespace

int runProposeLights(const ProposeLightsOptions& options) {
  if (options.scenes.empty()) throw InputError("propose-lights", "no scene given");
  ProposalEvaluation total;
  for (const fs::path& scene_file : options.scenes) {
    // One scene: its files straight into -o; several: one subfolder each, named after the scene's folder.
    const fs::path folder = options.scenes.size() == 1
                                ? options.output
                                : options.output / fs::absolute(scene_file).parent_path().filename();
    proposeOne(scene_file, folder, options, options.evaluate ? &total : nullptr);
  }
  if (!options.evaluate) return 0;
  const std::string table = proposalEvaluationTable(total);
  writeTextAtomically(options.output / "evaluation.md", table);
  std::cout << table;
  return 0;
}

}  // namespace solo::tools
