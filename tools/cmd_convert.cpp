#include "commands.h"

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/option_checks.h>
#include <solo/core/output_path.h>

#include <iostream>

namespace solo::tools {

int runConvert(const ConvertOptions& o) {
  requireOptionInRange(o.input_scale_m_per_unit, 0, 1e6, "--input-scale");
  requireOptionAboveAndAtMost(o.output_scale_m_per_unit, 0, 1e6, "--output-scale");
  refuseOutputThatIsAnInput(o.output, {o.input}, "output");
  if (o.kind == "depth") {
    DepthReadStats stats;
    const cv::Mat depth = readDepth(o.input, o.input_scale_m_per_unit, &stats);
    writeDepth(o.output, depth, o.output_scale_m_per_unit);
    std::cout << o.output.string() << ": " << depth.cols << "x" << depth.rows << " depth, " << stats.valid
              << " valid pixels, " << stats.invalid() << " invalid, " << stats.min_m << " to " << stats.max_m << " m\n";
  } else if (o.kind == "normals") {
    NormalReadStats stats;
    const cv::Mat normals = readNormals(o.input, &stats);
    writeNormals(o.output, normals);
    std::cout << o.output.string() << ": " << normals.cols << "x" << normals.rows << " normals, " << stats.valid
              << " valid, " << stats.invalid << " invalid, " << stats.renormalised << " renormalised\n";
  } else {
    throw InputError(o.input, "unknown map kind \"" + o.kind + "\" (depth or normals)");
  }
  return 0;
}

}  // namespace solo::tools
