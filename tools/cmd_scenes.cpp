// `solo scenes cityscapes|kitti|acdc ROOT -o DIR [--split S] [--depth D] [--normals N]`: a scene
// manifest per frame of a dataset, naming its files in place, and DIR/scenes.txt for
// `solo night --batch` (docs/datasets.md), by the library's walk (pipeline/dataset_scenes.h).
//
// Prints what was written, the frames left out and why, and the batch command to run next.

#include "commands.h"

#include <iostream>

namespace solo::tools {

int runScenes(const ScenesOptions& options) {
  DatasetScenesOptions walk = options.walk;
  walk.dataset = parseDataset(options.dataset, "dataset");
  const DatasetScenesResult result = writeDatasetScenes(walk);
  const std::size_t shown = 10;
  for (std::size_t k = 0; k < result.walk.skipped.size() && k < shown; ++k)
    std::cout << "skipped " << result.walk.skipped[k].image.string() << ": " << result.walk.skipped[k].reason << "\n";
  if (result.walk.skipped.size() > shown)
    std::cout << "... and " << result.walk.skipped.size() - shown << " more frames skipped\n";
  for (const std::string& note : result.walk.notes) std::cout << "note: " << note << "\n";
  std::cout << options.dataset << " " << options.walk.root.string() << ": " << result.manifests.size()
            << " manifests written, " << result.walk.skipped.size() << " frames skipped; splits: ";
  for (std::size_t k = 0; k < result.walk.splits.size(); ++k) std::cout << (k ? ", " : "") << result.walk.splits[k];
  if (result.walk.splits.empty()) std::cout << "(none)";
  std::cout << "\nlist: " << result.list.string() << "\nconvert: solo night --batch " << result.list.string()
            << " -o OUT_DIR --layout " << options.dataset << "\n"
            << std::flush;
  return 0;
}

}  // namespace solo::tools
