// Arrays, reports, arguments and progress shared by the binding files (bindings.h).

#include "bindings.h"

#include <pybind11/stl.h>

#include <cstring>

namespace solo::python {

namespace {

/// The numpy dtype of an OpenCV depth.
py::dtype dtypeOfDepth(int depth) {
  switch (depth) {
    case CV_8U: return py::dtype::of<std::uint8_t>();
    case CV_8S: return py::dtype::of<std::int8_t>();
    case CV_16U: return py::dtype::of<std::uint16_t>();
    case CV_16S: return py::dtype::of<std::int16_t>();
    case CV_32S: return py::dtype::of<std::int32_t>();
    case CV_32F: return py::dtype::of<float>();
    case CV_64F: return py::dtype::of<double>();
    default: throw std::invalid_argument("an OpenCV matrix of depth " + std::to_string(depth) + " has no numpy dtype");
  }
}

/// The OpenCV depth of a numpy dtype, or -1.
int depthOfDtype(const py::dtype& dtype) {
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'u' && size == 1) return CV_8U;
  if (kind == 'i' && size == 1) return CV_8S;
  if (kind == 'u' && size == 2) return CV_16U;
  if (kind == 'i' && size == 2) return CV_16S;
  if (kind == 'i' && size == 4) return CV_32S;
  if (kind == 'f' && size == 4) return CV_32F;
  if (kind == 'f' && size == 8) return CV_64F;
  if (kind == 'b' && size == 1) return CV_8U;
  return -1;
}

/// Keeps a heap object alive as long as a numpy array viewing it.
template <typename T>
py::capsule owner(T* object) {
  return py::capsule(object, [](void* p) { delete static_cast<T*>(p); });
}

}  // namespace

py::object matToArray(const cv::Mat& mat) {
  if (mat.empty()) return py::none();
  auto* held = new cv::Mat(mat);  // shares the pixels, counts a reference
  const py::capsule base = owner(held);
  const auto element = static_cast<py::ssize_t>(mat.elemSize1());
  std::vector<py::ssize_t> shape = {mat.rows, mat.cols};
  std::vector<py::ssize_t> strides = {static_cast<py::ssize_t>(mat.step[0]), static_cast<py::ssize_t>(mat.elemSize())};
  if (mat.channels() > 1) {
    shape.push_back(mat.channels());
    strides.push_back(element);
  }
  return py::array(dtypeOfDepth(mat.depth()), shape, strides, held->data, base);
}

py::array asArray(const py::handle& value, const py::dtype& dtype) {
  const py::module_ numpy = py::module_::import("numpy");
  return numpy.attr("ascontiguousarray")(value, dtype);
}

cv::Mat arrayToMat(const py::array& array, const std::string& what) {
  if (array.ndim() != 2 && array.ndim() != 3)
    throw py::value_error(what + ": expected an HxW or HxWxC array, got " + std::to_string(array.ndim()) +
                          " dimensions");
  const int depth = depthOfDtype(array.dtype());
  if (depth < 0)
    throw py::value_error(what + ": unsupported dtype " + py::str(array.dtype()).cast<std::string>() +
                          " (use uint8, uint16, int32, float32 or float64)");
  const int channels = array.ndim() == 3 ? static_cast<int>(array.shape(2)) : 1;
  if (channels < 1 || channels > CV_CN_MAX) throw py::value_error(what + ": " + std::to_string(channels) + " channels");
  if (array.shape(0) < 1 || array.shape(1) < 1) throw py::value_error(what + ": the array is empty");
  if (!(array.flags() & py::array::c_style))
    throw py::value_error(what + ": the array must be C-contiguous (numpy.ascontiguousarray)");
  return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), CV_MAKETYPE(depth, channels),
                 const_cast<void*>(array.data()), static_cast<std::size_t>(array.strides(0)));
}

py::tuple meshToArrays(TriangleMesh mesh) {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "vertices are packed");
  static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t), "faces are packed");
  auto* held = new TriangleMesh(std::move(mesh));
  const py::capsule base = owner(held);
  const auto n = static_cast<py::ssize_t>(held->vertices.size());
  const auto f = static_cast<py::ssize_t>(held->faces.size());
  py::array_t<double> vertices({n, py::ssize_t{3}}, n > 0 ? held->vertices.front().data() : nullptr, base);
  py::array_t<std::uint32_t> faces({f, py::ssize_t{3}}, f > 0 ? held->faces.front().data() : nullptr, base);
  return py::make_tuple(vertices, faces);
}

TriangleMesh arraysToMesh(const py::handle& vertices, const py::handle& faces) {
  const py::array_t<double, py::array::c_style | py::array::forcecast> v =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(vertices);
  const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> t =
      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(faces);
  if (!v || v.ndim() != 2 || v.shape(1) != 3) throw py::value_error("vertices: expected an Nx3 array");
  if (!t || t.ndim() != 2 || t.shape(1) != 3) throw py::value_error("faces: expected an Mx3 array of vertex indices");
  TriangleMesh mesh;
  mesh.vertices.resize(static_cast<std::size_t>(v.shape(0)));
  if (!mesh.vertices.empty()) std::memcpy(mesh.vertices.front().data(), v.data(), sizeof(double) * 3 * v.shape(0));
  mesh.faces.resize(static_cast<std::size_t>(t.shape(0)));
  const std::int64_t* index = t.data();
  for (std::size_t i = 0; i < mesh.faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t vertex = index[3 * i + k];
      if (vertex < 0 || vertex >= static_cast<std::int64_t>(mesh.vertices.size()))
        throw py::value_error("faces: face " + std::to_string(i) + " refers to vertex " + std::to_string(vertex) +
                              ", the mesh has " + std::to_string(mesh.vertices.size()));
      mesh.faces[i][k] = static_cast<std::uint32_t>(vertex);
    }
  return mesh;
}

py::object jsonLoads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

std::string jsonDumps(const py::handle& value) {
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

py::dict reportToDict(const RunReport& report) { return jsonLoads(reportToJson(report)); }

py::dict stageToDict(const StageReport& stage) {
  RunReport report;
  report.stages.push_back(stage);
  return reportToDict(report)["stages"].cast<py::list>()[0];
}

namespace {

py::object evaluationValue(const EvaluationValue& value) {
  return std::visit(
      [](const auto& x) -> py::object {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::monostate>) return py::none();
        else return py::cast(x);
      },
      value);
}

}  // namespace

py::dict recordToDict(const EvaluationRecord& record) {
  py::dict out;
  out["command"] = record.command;
  for (const auto& [section, fields] : {std::pair{"inputs", &record.inputs}, {"options", &record.options},
                                        {"metrics", &record.metrics}}) {
    py::dict values;
    for (const EvaluationField& f : *fields) values[py::str(f.key)] = evaluationValue(f.value);
    out[section] = values;
  }
  out["seconds"] = record.seconds;
  return out;
}

py::dict nightStatisticsToDict(const NightStatistics& s) {
  py::dict out;
  out["width_px"] = s.source_width_px;
  out["height_px"] = s.source_height_px;
  for (const NamedNightStatistic& n : namedNightStatistics(s)) {
    if (!n.value) out[py::str(n.key)] = py::none();
    else if (n.key == "halo_blobs") out[py::str(n.key)] = static_cast<std::int64_t>(*n.value);
    else out[py::str(n.key)] = *n.value;
  }
  return out;
}

std::filesystem::path toPath(const py::handle& value, const std::string& what) {
  const py::module_ os = py::module_::import("os");
  if (!py::isinstance<py::str>(value) && !py::hasattr(value, "__fspath__"))
    throw py::type_error(what + ": expected a path (str or os.PathLike), got " +
                         py::str(value.get_type().attr("__name__")).cast<std::string>());
  return std::filesystem::path(os.attr("fspath")(value).cast<std::string>());
}

std::optional<std::filesystem::path> toOptionalPath(const py::handle& value, const std::string& what) {
  if (value.is_none()) return std::nullopt;
  return toPath(value, what);
}

PinholeCamera cameraFromDict(const py::handle& camera, const std::string& what) {
  if (!py::isinstance<py::dict>(camera))
    throw py::type_error(what + ": expected a dict with fx, fy, cx, cy (pixels) and optionally width, height");
  const py::dict c = py::reinterpret_borrow<py::dict>(camera);
  PinholeCamera out;
  const auto number = [&](const char* key, bool required) -> double {
    if (!c.contains(key)) {
      if (required) throw py::value_error(what + ": missing \"" + key + "\"");
      return 0;
    }
    return py::cast<double>(c[key]);
  };
  out.fx = number("fx", true);
  out.fy = number("fy", true);
  out.cx = number("cx", true);
  out.cy = number("cy", true);
  out.width = static_cast<int>(number("width", false));
  out.height = static_cast<int>(number("height", false));
  for (const auto& item : c) {
    const std::string key = py::str(item.first);
    if (key != "fx" && key != "fy" && key != "cx" && key != "cy" && key != "width" && key != "height")
      throw py::value_error(what + ": unknown key \"" + key + "\" (fx, fy, cx, cy, width, height)");
  }
  return out;
}

py::dict cameraToDict(const PinholeCamera& camera) {
  py::dict d;
  d["fx"] = camera.fx;
  d["fy"] = camera.fy;
  d["cx"] = camera.cx;
  d["cy"] = camera.cy;
  d["width"] = camera.width;
  d["height"] = camera.height;
  return d;
}

Progress::Progress(py::object callback, std::vector<std::string> stages)
    : callback_(std::move(callback)), stages_(std::move(stages)) {
  if (!callback_.is_none() && !PyCallable_Check(callback_.ptr()))
    throw py::type_error("progress: expected a callable progress(stage, fraction) or None");
}

void Progress::stage(const std::string& name) const {
  if (callback_.is_none()) return;
  std::size_t index = 0;
  while (index < stages_.size() && stages_[index] != name) ++index;
  const double fraction = stages_.empty() ? 0.0 : static_cast<double>(std::min(index, stages_.size())) / stages_.size();
  const py::gil_scoped_acquire gil;
  callback_(name, fraction);
}

void Progress::done() const {
  if (callback_.is_none()) return;
  callback_("done", 1.0);
}

}  // namespace solo::python
