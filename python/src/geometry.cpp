// Geometry: depth refinement (`solo depth`), the mesh of a depth map (`solo mesh from-depth`),
// mesh repair (`solo mesh clean`) and mesh files, on numpy arrays.

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/geometry/depth_refinement.h>
#include <solo/geometry/mesh_cleanup.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_job.h>

#include <pybind11/stl.h>

namespace solo::python {

namespace {

DepthOptimizer optimizerNamed(const std::string& name) {
  if (name == "ceres") return DepthOptimizer::Ceres;
  if (name == "adam") return DepthOptimizer::Adam;
  throw InputError("--optimizer", "unknown optimiser \"" + name + "\" (use ceres or adam)");
}

TangentModel tangentModelNamed(const std::string& name) {
  if (name == "perspective") return TangentModel::Perspective;
  if (name == "paper") return TangentModel::PaperGraph;
  throw InputError("--tangent-model", "unknown tangent model \"" + name + "\" (use perspective or paper)");
}

/// The refinement's results at the image resolution and the run report `solo depth` writes.
py::dict refinementToDict(const DepthRefinementResult& r, const RunReport& report) {
  py::dict out;
  out["depth"] = matToArray(r.depth_m);
  out["normals"] = matToArray(r.depth_normals);
  out["uncertain"] = matToArray(r.uncertain);
  out["predicted_normals"] = matToArray(r.normals);
  out["upsampled_depth"] = matToArray(r.upsampled_depth_m);
  out["completed_depth"] = matToArray(r.completed_depth_m);
  out["filtered_depth"] = matToArray(r.filtered_depth_m);
  out["filled"] = matToArray(r.filled);
  out["report"] = reportToDict(report);
  return out;
}

py::dict refineDepthBinding(const PySceneHandle& scene, bool upsample, bool complete, bool filter, bool uncertain,
                            bool optimize, const std::string& optimizer, const std::string& tangent_model,
                            int optimize_iterations, double optimize_tolerance, const py::object& callback) {
  DepthRefinementOptions options;
  options.upsampling.enabled = upsample;
  options.complete = complete;
  options.filter = filter;
  options.uncertain_regions = uncertain;
  options.optimize = optimize;
  options.optimizer = optimizerNamed(optimizer);
  options.optimization.objective.tangent_model = tangentModelNamed(tangent_model);
  options.adam.objective.tangent_model = options.optimization.objective.tangent_model;
  if (optimize_iterations > 0) options.optimization.max_iterations = optimize_iterations;
  if (optimize_tolerance >= 0) options.optimization.function_tolerance = optimize_tolerance;
  const Progress progress(callback, {"refine"});
  progress.stage("refine");
  RunReport report;
  report.command = "depth";
  report.scene = scene->scene.manifest.file.string();
  report.versions = pipelineDependencyVersions();
  DepthRefinementResult result;
  {
    const py::gil_scoped_release release;
    const Stopwatch total;
    report.stages.push_back(sceneInputReport(scene->scene, 0));
    result = refineDepth(sceneForRefinement(scene->scene), options);
    for (const StageReport& step : result.steps) report.stages.push_back(step);
    report.stages.push_back(result.report);
    report.total_seconds = total.seconds();
  }
  progress.done();
  return refinementToDict(result, report);
}

/// `solo mesh from-depth`'s check: a face needs a 2x2 block of valid depth pixels.
void requireAFaceOfDepth(const cv::Mat& depth, const std::filesystem::path& source) {
  for (int y = 0; y + 1 < depth.rows; ++y) {
    const float* row = depth.ptr<float>(y);
    const float* below = depth.ptr<float>(y + 1);
    for (int x = 0; x + 1 < depth.cols; ++x)
      if (row[x] > 0 && row[x + 1] > 0 && below[x] > 0 && below[x + 1] > 0) return;
  }
  throw InputError(source, "no 2x2 block of valid depth pixels in the " + std::to_string(depth.cols) + "x" +
                               std::to_string(depth.rows) + " map: a mesh face needs one, the mesh would be empty");
}

/// The maps the mesh is made from: the scene's (its street lights as instances of their own,
/// as `solo mesh from-depth` and `solo night` see them), or arrays with a camera dict.
struct MeshInput {
  cv::Mat depth_m, instances, uncertain, normals;
  PinholeCamera camera;
  std::filesystem::path source = "depth";
  std::vector<py::object> arrays;  // viewed by the Mats
  std::int64_t street_light_pixels = -1;
};

MeshInput meshInput(const py::object& scene, const py::object& depth, const py::object& camera,
                    const py::object& instances, const py::object& uncertain, const py::object& normals) {
  MeshInput in;
  const auto view = [&in](const py::object& value, const py::dtype& dtype, const std::string& what) {
    const py::array array = asArray(value, dtype);
    in.arrays.push_back(array);
    return arrayToMat(array, what);
  };
  if (!scene.is_none()) {
    const Scene& s = scene.cast<PySceneHandle>()->scene;
    in.depth_m = s.depth_m;
    in.camera = s.camera;
    in.source = s.manifest.depth;
    in.street_light_pixels = 0;
    in.instances = sceneForRefinement(s, &in.street_light_pixels).instances;
    in.normals = s.normals;
  } else {
    if (depth.is_none() || camera.is_none())
      throw py::type_error("mesh_from_depth: give a scene, or depth and camera");
    in.depth_m = view(depth, py::dtype::of<float>(), "depth");
    in.camera = cameraFromDict(camera, "camera");
    if (in.camera.width <= 0) {
      in.camera.width = in.depth_m.cols;
      in.camera.height = in.depth_m.rows;
    }
    validateCamera(in.camera, "camera");
    if (!instances.is_none()) in.instances = view(instances, py::dtype::of<std::int32_t>(), "instances");
  }
  if (!uncertain.is_none()) in.uncertain = view(uncertain, py::dtype::of<std::uint8_t>(), "uncertain");
  if (!normals.is_none()) {
    in.normals = view(normals, py::dtype::of<float>(), "normals");
    if (in.normals.channels() != 3) throw InputError("normals", "normals must have three channels (HxWx3)");
  }
  if (in.depth_m.channels() != 1) throw InputError(in.source, "depth must have one channel");
  return in;
}

py::dict meshFromDepthBinding(const py::object& scene, const py::object& depth, const py::object& camera,
                              const py::object& instances, const py::object& uncertain, const py::object& normals,
                              bool solids, bool backdrops, bool fill_holes, bool evaluate) {
  const MeshInput in = meshInput(scene, depth, camera, instances, uncertain, normals);
  DepthMeshCleanupOptions options;
  options.close_solids = solids;
  options.backdrops = backdrops;
  options.fill_holes = fill_holes;
  options.evaluate = evaluate;
  StageReport stage;
  TriangleMesh triangles;
  {
    const py::gil_scoped_release release;
    requireAFaceOfDepth(in.depth_m, in.source);
    const DepthMesh mesh =
        meshFromScene(in.depth_m, in.camera, in.instances, in.uncertain, options, stage, {}, {}, in.normals);
    if (in.street_light_pixels >= 0) stage.add("street_light_pixels_relabelled", in.street_light_pixels);
    triangles = toTriangleMesh(mesh.mesh);
  }
  if (triangles.faces.empty()) throw InputError(in.source, "the mesh has no face after the clean-up: nothing to write");
  const py::tuple arrays = meshToArrays(std::move(triangles));
  py::dict out;
  out["vertices"] = arrays[0];
  out["faces"] = arrays[1];
  out["report"] = stageToDict(stage);
  return out;
}

py::dict cleanMeshBinding(const py::object& mesh, const py::object& faces, bool fill_holes) {
  MeshCleanupOptions options;
  options.fill_holes = fill_holes;
  TriangleMesh input;
  std::filesystem::path source = "mesh";
  double read_seconds = 0;
  if (faces.is_none()) {
    source = toPath(mesh, "mesh");
    const py::gil_scoped_release release;
    const Stopwatch clock;
    input = readMesh(source);
    read_seconds = clock.seconds();
  } else {
    input = arraysToMesh(mesh, faces);
  }
  StageReport stage;
  TriangleMesh output;
  {
    const py::gil_scoped_release release;
    output = cleanMesh(input, options, stage, source);
  }
  if (faces.is_none()) stage.metrics.insert(stage.metrics.begin(), Metric{"seconds_read", read_seconds, "s"});
  stage.seconds += read_seconds;
  if (output.faces.empty()) throw InputError(source, "the mesh has no face: nothing to write");
  const py::tuple arrays = meshToArrays(std::move(output));
  py::dict out;
  out["vertices"] = arrays[0];
  out["faces"] = arrays[1];
  out["report"] = stageToDict(stage);
  return out;
}

}  // namespace

void bindGeometry(py::module_& m) {
  m.def("refine_depth", &refineDepthBinding, py::arg("scene"), py::kw_only(), py::arg("upsample") = true,
        py::arg("complete") = true, py::arg("filter") = true, py::arg("uncertain") = true, py::arg("optimize") = true,
        py::arg("optimizer") = "ceres", py::arg("tangent_model") = "perspective", py::arg("optimize_iterations") = 0,
        py::arg("optimize_tolerance") = -1.0, py::arg("progress") = py::none(),
        "Depth refinement as `solo depth` runs it: upsampling, completion, instance filter, uncertain regions, "
        "normal-guided optimisation. optimize_iterations 0 and optimize_tolerance < 0 keep the library's defaults.");
  m.def("mesh_from_depth", &meshFromDepthBinding, py::arg("scene") = py::none(), py::kw_only(),
        py::arg("depth") = py::none(), py::arg("camera") = py::none(), py::arg("instances") = py::none(),
        py::arg("uncertain") = py::none(), py::arg("normals") = py::none(), py::arg("solids") = true, py::arg("backdrops") = true,
        py::arg("fill_holes") = true, py::arg("evaluate") = true,
        "The mesh stage as `solo mesh from-depth` runs it, on a scene or on a depth array (metres) and a camera "
        "dict: {vertices Nx3 float64 m, faces Mx3 uint32, report}.");
  m.def("clean_mesh", &cleanMeshBinding, py::arg("mesh"), py::arg("faces") = py::none(), py::kw_only(),
        py::arg("fill_holes") = true,
        "Mesh repair and hole filling as `solo mesh clean` runs it, on a mesh file or on vertices (Nx3) and faces "
        "(Mx3): {vertices, faces, report}.");
  m.def("read_mesh", [](const py::object& file) {
          TriangleMesh mesh;
          const std::filesystem::path path = toPath(file, "file");
          {
            const py::gil_scoped_release release;
            mesh = readMesh(path);
          }
          return meshToArrays(std::move(mesh));
        }, py::arg("file"), "(vertices Nx3 float64, faces Mx3 uint32) of an OFF, OBJ, PLY or STL file.");
  m.def("write_mesh", [](const py::object& file, const py::object& vertices, const py::object& faces) {
          const TriangleMesh mesh = arraysToMesh(vertices, faces);
          const std::filesystem::path path = toPath(file, "file");
          const py::gil_scoped_release release;
          writeMesh(path, mesh);
        }, py::arg("file"), py::arg("vertices"), py::arg("faces"),
        "Writes OFF, OBJ, PLY (binary) or STL by extension, atomically.");
}

}  // namespace solo::python
