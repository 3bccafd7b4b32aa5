// `solo synth`: a synthetic street written as a scene folder (synth/scene_folder.h), and the
// run's summary on the terminal.

#include "commands.h"

#include <solo/core/report.h>
#include <solo/synth/scene_folder.h>

#include <iostream>

namespace solo::tools {

int runSynth(const SynthOptions& o) {
  SyntheticSceneOptions options = o;
  options.progress = true;
  const SyntheticSceneResult result = writeSyntheticScene(o.output, options);
  std::cout << reportSummary(result.report) << "scene: " << result.manifest.string() << "\n";
  return 0;
}

}  // namespace solo::tools
