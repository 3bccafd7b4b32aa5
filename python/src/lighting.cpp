// Lights: the light stage as `solo lights` runs it (groups and probabilistic instantiation),
// the light record as a dict (the JSON of docs/lighting.md).

#include "bindings.h"

#include <solo/lighting/light_record.h>
#include <solo/lighting/light_stage.h>
#include <solo/pipeline/data_dir.h>

#include <pybind11/stl.h>

namespace solo::python {

namespace {

py::dict proposeLights(const PySceneHandle& scene, std::uint64_t seed, bool ablation, double ablation_luminance,
                       const py::object& table, const py::object& depth) {
  LightStageOptions options;
  options.instantiation.seed = seed;
  options.instantiation.ablation = ablation;
  options.instantiation.ablation_luminance_cd_m2 = ablation_luminance;
  if (const auto path = toOptionalPath(table, "table")) options.illuminant_table = *path;
  validateLightStageOptions(options);
  py::object depth_array = py::none();
  cv::Mat depth_m;
  if (!depth.is_none()) {
    depth_array = asArray(depth, py::dtype::of<float>());
    depth_m = arrayToMat(depth_array, "depth");
  }
  LightStageResult result;
  {
    const py::gil_scoped_release release;
    if (options.illuminant_table.empty()) options.illuminant_table = defaultIlluminantTable();
    result = runLightStage(scene->scene, depth_m, options);
  }
  py::dict out;
  out["record"] = jsonLoads(lightRecordJson(result.record));
  out["report"] = stageToDict(result.report);
  return out;
}

}  // namespace

void bindLighting(py::module_& m) {
  m.def("propose_lights", &proposeLights, py::arg("scene"), py::kw_only(), py::arg("seed") = 0,
        py::arg("ablation") = false, py::arg("ablation_luminance") = 1000.0, py::arg("table") = py::none(),
        py::arg("depth") = py::none(),
        "The light stage as `solo lights` runs it: light groups, probabilistic instantiation with the illuminant "
        "table (None: the bundled one), geometry measured on `depth` (metres at the image resolution; None: the "
        "scene's depth). Returns {record: the light record as a dict (docs/lighting.md), report}.");
  m.def("read_light_record", [](const py::object& file) {
          return jsonLoads(lightRecordJson(readLightRecord(toPath(file, "file"))));
        }, py::arg("file"), "A light record file, validated, as a dict.");
}

}  // namespace solo::python
