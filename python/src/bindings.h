#pragma once
// What the binding files of the Python module share: numpy arrays as cv::Mat and back without
// copying, reports and records as Python dicts, the scene held with the arrays it views, and a
// progress callback called with the GIL held. docs/python.md describes the module.

#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/pipeline/evaluation_record.h>
#include <solo/post/night_statistics.h>

#include <opencv2/core.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace solo::python {

namespace py = pybind11;

// ---- arrays ----------------------------------------------------------------------------

/// A numpy view of `mat` (no copy): HxW for one channel, HxWxC otherwise; the array keeps a
/// reference to the pixels. An empty Mat is None.
py::object matToArray(const cv::Mat& mat);

/// The pixels of a C-contiguous numpy array as a cv::Mat without copying (any other layout is
/// copied into one). `what` names the argument in errors: ValueError for an array that is not
/// HxW (channels 1) or HxWxC. The caller keeps the array alive as long as the Mat.
cv::Mat arrayToMat(const py::array& array, const std::string& what);

/// A numpy array of the given dtype (C-contiguous; cast when it is another dtype), or None.
py::array asArray(const py::handle& value, const py::dtype& dtype);

/// A mesh as numpy views: vertices Nx3 float64 metres, faces Mx3 uint32, owning the mesh.
py::tuple meshToArrays(TriangleMesh mesh);
/// Vertices Nx3 and faces Mx3 (any numeric types) as a mesh; ValueError for other shapes.
TriangleMesh arraysToMesh(const py::handle& vertices, const py::handle& faces);

// ---- reports and records ---------------------------------------------------------------

/// The run report as the dict of its JSON (reportToJson).
py::dict reportToDict(const RunReport& report);
/// One stage's report as a dict (the stage object of reportToJson).
py::dict stageToDict(const StageReport& stage);
/// An evaluation record as the dict `solo eval ... --json` prints.
py::dict recordToDict(const EvaluationRecord& record);
/// The realism statistics as `solo eval night --json` writes an image's: width_px, height_px and
/// every statistic by its key (None where it has none; halo_blobs a whole number).
py::dict nightStatisticsToDict(const NightStatistics& statistics);
/// A JSON text as Python objects (json.loads).
py::object jsonLoads(const std::string& text);
/// A Python object as JSON text (json.dumps).
std::string jsonDumps(const py::handle& value);

// ---- arguments -------------------------------------------------------------------------

/// A str or os.PathLike as a path; TypeError naming `what` otherwise.
std::filesystem::path toPath(const py::handle& value, const std::string& what);
/// None, or a path.
std::optional<std::filesystem::path> toOptionalPath(const py::handle& value, const std::string& what);
/// The camera of a dict {"fx", "fy", "cx", "cy"[, "width", "height"]} (pixels).
PinholeCamera cameraFromDict(const py::handle& camera, const std::string& what);
py::dict cameraToDict(const PinholeCamera& camera);

// ---- scenes ----------------------------------------------------------------------------

/// A loaded scene and the numpy arrays its maps view (kept alive with it).
struct PyScene {
  Scene scene;
  std::vector<py::object> arrays;
};
using PySceneHandle = std::shared_ptr<PyScene>;

// ---- progress --------------------------------------------------------------------------

/// A Python callable progress(stage, fraction) called from C++ with the GIL held, or nothing.
class Progress {
 public:
  Progress(py::object callback, std::vector<std::string> stages);
  /// Calls back with the stage and the share of the stages before it.
  void stage(const std::string& name) const;
  /// Calls back ("done", 1.0).
  void done() const;
  bool enabled() const { return !callback_.is_none(); }

 private:
  py::object callback_;
  std::vector<std::string> stages_;
};

// ---- the binding of each area ----------------------------------------------------------

void bindErrors(py::module_& m);
void bindScene(py::module_& m);
void bindGeometry(py::module_& m);
void bindLighting(py::module_& m);
void bindNight(py::module_& m);
void bindPost(py::module_& m);
void bindEval(py::module_& m);

}  // namespace solo::python
