// Scenes: read from a manifest, or made from numpy arrays with the checks and conventions of
// loadScene (docs/scene-format.md); the map readers and writers of solo_core.

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/scene_from_arrays.h>
#include <solo/pipeline/data_dir.h>
#include <solo/pipeline/night_job.h>

#include <pybind11/stl.h>

#include <cmath>

namespace solo::python {

namespace {

/// What describeScene reports of an array: "array WxH Cch dtype".
ImageFileInfo arrayInfo(const py::array& array) {
  ImageFileInfo info;
  info.format = "array";
  info.height = static_cast<int>(array.shape(0));
  info.width = static_cast<int>(array.shape(1));
  info.channels = array.ndim() == 3 ? static_cast<int>(array.shape(2)) : 1;
  info.pixel_type = py::str(array.dtype()).cast<std::string>();
  return info;
}

double maxCode(int depth) { return depth == CV_8U ? 255.0 : depth == CV_16U ? 65535.0 : 1.0; }

/// A contiguous array of `value` that the scene keeps, its info recorded as map `name`.
py::array keepArray(PyScene& s, const py::handle& value, const std::string& name) {
  py::array array = py::module_::import("numpy").attr("ascontiguousarray")(value);
  s.arrays.push_back(array);
  s.scene.maps.push_back({name, name, arrayInfo(array)});
  return array;
}

/// The day image (or albedo) as readColorImage makes it: CV_32FC3 in [0, 1], integer codes
/// divided by their largest value, one channel repeated, alpha dropped; float32 is viewed.
cv::Mat colourMap(const py::array& array, const std::string& name) {
  const cv::Mat native = arrayToMat(array, name);
  const int channels = native.channels();
  if (channels != 1 && channels != 3 && channels != 4)
    throw InputError(name, "colour image needs 1, 3 or 4 channels, found " + std::to_string(channels));
  if (native.depth() == CV_32S) throw InputError(name, "colour image must be 8/16-bit or float, found int32");
  if (native.type() == CV_32FC3) return native;
  cv::Mat rgb;
  if (channels == 1) {
    cv::merge(std::vector<cv::Mat>{native, native, native}, rgb);
  } else if (channels == 4) {
    std::vector<cv::Mat> planes;
    cv::split(native, planes);
    planes.resize(3);
    cv::merge(planes, rgb);
  } else {
    rgb = native;
  }
  cv::Mat out;
  rgb.convertTo(out, CV_32FC3, 1.0 / maxCode(native.depth()));
  return out;
}

/// Sets NaN and infinite values of a float map to 0 (on a copy when there are any), as loadScene
/// does; a warning counts them.
void zeroNonFinite(cv::Mat& map, const char* name, std::vector<std::string>& warnings) {
  if (map.empty() || map.depth() != CV_32F) return;
  const cv::Mat flat = map.reshape(1);
  if (cv::checkRange(flat, true)) return;
  cv::Mat repaired = map.clone();
  std::int64_t count = 0;
  repaired.reshape(1).forEach<float>([&count](float& v, const int*) {
    if (!std::isfinite(v)) v = 0.f;
  });
  for (int y = 0; y < flat.rows; ++y)
    for (int x = 0; x < flat.cols; ++x) count += !std::isfinite(flat.at<float>(y, x));
  map = repaired;
  warnings.push_back(std::to_string(count) + " NaN or infinite values of the " + name + " set to 0");
}

/// Depth in metres as readDepth makes it (invalid = 0, counted); float32 without a scale is
/// viewed unless it holds NaN, inf or negative values.
cv::Mat depthMap(const py::array& array, double scale_m_per_unit, DepthReadStats& s) {
  const cv::Mat native = arrayToMat(array, "depth");
  if (native.channels() != 1) throw InputError("depth", "depth must have one channel, found " + std::to_string(native.channels()));
  if (native.depth() == CV_8U) throw InputError("depth", "8-bit depth has only 256 levels; give 16-bit or float depth");
  const bool integer = native.depth() != CV_32F && native.depth() != CV_64F;
  if (integer && !(scale_m_per_unit > 0))
    throw InputError("depth", "integer depth needs depth_scale, metres per unit (1/256 for KITTI, 0.001 for millimetres)");
  if (!std::isfinite(scale_m_per_unit)) throw InputError("depth", "depth_scale is not finite");
  const double scale = scale_m_per_unit > 0 ? scale_m_per_unit : 1.0;
  cv::Mat values;
  native.convertTo(values, CV_64F);
  cv::Mat depth(values.rows, values.cols, CV_32F);
  double lo = INFINITY, hi = -INFINITY;
  bool changed = scale != 1.0 || native.depth() != CV_32F;
  for (int y = 0; y < values.rows; ++y) {
    const double* src = values.ptr<double>(y);
    float* dst = depth.ptr<float>(y);
    for (int x = 0; x < values.cols; ++x) {
      const double v = src[x];
      float d = 0.f;
      if (std::isnan(v)) ++s.nan;
      else if (std::isinf(v)) ++s.inf;
      else if (v < 0) ++s.negative;
      else if (v == 0) ++s.zero;
      else {
        const double m = v * scale;
        if (!std::isfinite(static_cast<float>(m)) || static_cast<float>(m) <= 0.f) {
          ++s.inf;
        } else {
          ++s.valid;
          d = static_cast<float>(m);
          lo = std::min(lo, m);
          hi = std::max(hi, m);
        }
      }
      changed = changed || d != native.at<float>(y, x) || std::isnan(native.at<float>(y, x));
      dst[x] = d;
    }
  }
  s.min_m = s.valid ? lo : 0;
  s.max_m = s.valid ? hi : 0;
  if (s.valid == 0) throw InputError("depth", "depth has no valid pixel (all 0, NaN, inf or negative)");
  return changed ? depth : native;
}

/// Unit normals as readNormals makes them: 8/16-bit codes v / max * 2 - 1 ((0,0,0) invalid),
/// float vectors as given; every valid vector renormalised, invalid ones (0,0,0). Always a copy.
cv::Mat normalMap(const py::array& array, NormalReadStats& s) {
  return decodeNormals(arrayToMat(array, "normals"), "normals", s);
}

/// A scalar map (roughness) as readScalarMap makes it: CV_32F, integer codes divided by their
/// largest value; float32 viewed.
cv::Mat scalarMap(const py::array& array, const std::string& name) {
  const cv::Mat native = arrayToMat(array, name);
  if (native.channels() != 1) throw InputError(name, "scalar map must have one channel, found " + std::to_string(native.channels()));
  if (native.depth() == CV_32S) throw InputError(name, "scalar map must be 8/16-bit or float, found int32");
  if (native.depth() == CV_32F) return native;
  cv::Mat out;
  native.convertTo(out, CV_32F, 1.0 / maxCode(native.depth()));
  return out;
}

/// A label map as readLabels makes it: CV_32S (int32 viewed), no negative id.
cv::Mat labelMap(const py::array& array, const std::string& name) {
  const cv::Mat native = arrayToMat(array, name);
  if (native.channels() != 1) throw InputError(name, "label map must have one channel, found " + std::to_string(native.channels()));
  if (native.depth() != CV_8U && native.depth() != CV_16U && native.depth() != CV_32S)
    throw InputError(name, "label map must hold integers (uint8, uint16 or int32)");
  cv::Mat labels = native;
  if (native.depth() != CV_32S) native.convertTo(labels, CV_32S);
  double lo = 0, hi = 0;
  cv::minMaxLoc(labels, &lo, &hi);
  if (lo < 0) throw InputError(name, name + " holds negative ids");
  return labels;
}

/// Ids held in 64-bit or unsigned 32-bit integers (numpy's default int) as int32, refused
/// outside its range; other arrays as they are.
py::object int32Ids(const py::object& value, const std::string& name) {
  const py::module_ numpy = py::module_::import("numpy");
  py::array array = numpy.attr("asarray")(value);
  const char kind = array.dtype().kind();
  if (!((kind == 'i' && array.dtype().itemsize() == 8) || (kind == 'u' && array.dtype().itemsize() >= 4)))
    return std::move(array);
  if (array.size() > 0) {
    const py::object lo = numpy.attr("min")(array).attr("item")();
    const py::object hi = numpy.attr("max")(array).attr("item")();
    if (lo.attr("__lt__")(0).cast<bool>() || hi.attr("__gt__")(INT32_MAX).cast<bool>())
      throw InputError(name, name + " holds ids outside 0.." + std::to_string(INT32_MAX));
  }
  return array.attr("astype")(numpy.attr("int32"));
}

void checkLightIds(const cv::Mat& lights) {
  for (int y = 0; y < lights.rows; ++y)
    for (int x = 0; x < lights.cols; ++x) {
      const int id = lights.at<int>(y, x);
      const int category = id / 1000;
      if (id != 0 && (category < 1 || category > kLightCategoryCount))
        throw InputError("lights", "light id " + std::to_string(id) + " at pixel (" + std::to_string(x) + ", " +
                                       std::to_string(y) + ") has category " + std::to_string(category) +
                                       ", expected categoryId * 1000 + k with categoryId in 1.." +
                                       std::to_string(kLightCategoryCount));
    }
}

/// The camera of the scene: the dict's (resolution 0: the image's), validated and scaled to the
/// image, or defaultSceneCamera with loadScene's warning.
void setCamera(const py::handle& camera, Scene& s) {
  if (camera.is_none()) {
    const PinholeCamera c = defaultSceneCamera(s.image.cols, s.image.rows);
    s.camera_is_default = true;
    s.warnings.push_back(defaultCameraWarning(c));
    setCameraForImage(c, "camera", s);
  } else {
    setCameraForImage(cameraFromDict(camera, "camera"), "camera", s);
  }
}


struct SceneArrays {
  py::object image, depth, normals, albedo, roughness, instances, labels, lights, light_groups, camera;
  double depth_scale = 0;
  std::string name;
};

/// The optional label maps, labels derived from instances when only those are given.
void setLabelMaps(const SceneArrays& a, PyScene& p) {
  Scene& s = p.scene;
  const auto optional = [&](const py::object& value, const char* name, cv::Mat& out) {
    if (!value.is_none()) out = labelMap(keepArray(p, int32Ids(value, name), name), name);
  };
  optional(a.instances, "instances", s.instances);
  optional(a.labels, "labels", s.labels);
  optional(a.lights, "lights", s.lights);
  optional(a.light_groups, "light_groups", s.light_groups);
  if (!s.lights.empty()) checkLightIds(s.lights);
  if (s.labels.empty() && !s.instances.empty()) {
    s.labels = s.instances.clone();
    s.labels.forEach<int>([](int& v, const int*) { v = cityscapesClassOfInstance(v); });
    s.warnings.push_back("labelIds derived from instanceIds");
  }
}

/// A scene from arrays, as loadScene makes one from files: the maps converted as the readers
/// convert files, the same checks, warnings and camera.
PySceneHandle sceneFromArrays(const SceneArrays& a) {
  auto p = std::make_shared<PyScene>();
  Scene& s = p->scene;
  s.manifest.file = a.name;
  s.manifest.image = "image";
  s.manifest.depth = "depth";
  s.image = colourMap(keepArray(*p, a.image, "image"), "image");
  s.depth_m = depthMap(keepArray(*p, a.depth, "depth"), a.depth_scale, s.depth_stats);
  if (!a.normals.is_none()) {
    NormalReadStats stats;
    s.normals = normalMap(keepArray(*p, a.normals, "normals"), stats);
    s.normal_stats = stats;
    s.manifest.normals = "normals";
  }
  if (!a.albedo.is_none()) s.albedo = colourMap(keepArray(*p, a.albedo, "albedo"), "albedo");
  if (!a.roughness.is_none()) s.roughness = scalarMap(keepArray(*p, a.roughness, "roughness"), "roughness");
  setLabelMaps(a, *p);
  zeroNonFinite(s.image, "day image", s.warnings);
  zeroNonFinite(s.albedo, "albedo", s.warnings);
  zeroNonFinite(s.roughness, "roughness", s.warnings);
  setCamera(a.camera, s);
  if (!s.normals.empty()) s.normal_stats->back_facing = countBackFacingNormals(s.normals, s.camera);
  for (const auto& [name, map] : {std::pair<const char*, const cv::Mat*>{"depth", &s.depth_m}, {"normals", &s.normals},
                                  {"albedo", &s.albedo}, {"roughness", &s.roughness}, {"instances", &s.instances},
                                  {"labels", &s.labels}, {"lights", &s.lights}, {"light_groups", &s.light_groups}})
    if (!map->empty() && map->size() != s.image.size() &&
        std::abs(static_cast<double>(map->cols) / map->rows / (static_cast<double>(s.image.cols) / s.image.rows) -
                 1.0) > 0.01)
      s.warnings.push_back(std::string(name) + " is " + sizeText(*map) + ", a different aspect ratio than the " +
                           sizeText(s.image) + " image: it will be stretched when upsampled");
  if (s.normal_stats && s.normal_stats->renormalised > 0)
    s.warnings.push_back(std::to_string(s.normal_stats->renormalised) + " normals were not unit length: renormalised");
  return p;
}

void bindSceneClass(py::module_& m) {
  py::class_<PyScene, PySceneHandle>(m, "Scene",
                                     "A loaded scene (load_scene, scene_from_arrays). Its maps are numpy views at "
                                     "their own resolution; an absent map is None.")
      .def_property_readonly("image", [](const PyScene& p) { return matToArray(p.scene.image); },
                             "HxWx3 float32 sRGB-encoded RGB in [0, 1]")
      .def_property_readonly("depth", [](const PyScene& p) { return matToArray(p.scene.depth_m); },
                             "float32 z-depth in metres, 0 = invalid")
      .def_property_readonly("normals", [](const PyScene& p) { return matToArray(p.scene.normals); },
                             "float32 unit normals, camera frame (x right, y down, z forward), (0,0,0) = invalid")
      .def_property_readonly("albedo", [](const PyScene& p) { return matToArray(p.scene.albedo); })
      .def_property_readonly("roughness", [](const PyScene& p) { return matToArray(p.scene.roughness); })
      .def_property_readonly("instances", [](const PyScene& p) { return matToArray(p.scene.instances); })
      .def_property_readonly("labels", [](const PyScene& p) { return matToArray(p.scene.labels); })
      .def_property_readonly("lights", [](const PyScene& p) { return matToArray(p.scene.lights); })
      .def_property_readonly("light_groups", [](const PyScene& p) { return matToArray(p.scene.light_groups); })
      .def_property_readonly("camera", [](const PyScene& p) { return cameraToDict(p.scene.camera); },
                             "intrinsics at the image resolution, pixels")
      .def_property_readonly("camera_is_default", [](const PyScene& p) { return p.scene.camera_is_default; })
      .def_property_readonly("width", [](const PyScene& p) { return p.scene.width(); })
      .def_property_readonly("height", [](const PyScene& p) { return p.scene.height(); })
      .def_property_readonly("manifest", [](const PyScene& p) { return p.scene.manifest.file.string(); },
                             "the manifest read, or the name given to scene_from_arrays")
      .def_property_readonly("warnings", [](const PyScene& p) { return p.scene.warnings; })
      .def("describe", [](const PyScene& p) { return stageToDict(sceneInputReport(p.scene, 0)); },
           "The input stage of a run report: map sizes, invalid counts, camera, warnings.")
      .def("__repr__", [](const PyScene& p) {
        return "<solo.Scene " + p.scene.manifest.file.string() + " " + sizeText(p.scene.image) + ">";
      });
}

/// An image file's pixels in the file's own integer type (uint8, uint16, int32) or float32.
cv::Mat readStoredImage(const std::filesystem::path& file) {
  ImageFileInfo info;
  cv::Mat pixels;
  {
    const py::gil_scoped_release release;
    pixels = readImageRaw(file, &info);
  }
  const int depth = info.pixel_type == "uint8"    ? CV_8U
                    : info.pixel_type == "uint16" ? CV_16U
                    : info.pixel_type == "int32"  ? CV_32S
                                                  : -1;
  if (depth < 0) return pixels;
  cv::Mat codes;
  pixels.convertTo(codes, CV_MAKETYPE(depth, pixels.channels()));
  return codes;
}

void bindReaders(py::module_& m) {
  m.def("read_image", [](const py::object& file) { return matToArray(readStoredImage(toPath(file, "file"))); },
        py::arg("file"), "A PNG, JPEG, TIFF, EXR, PFM or NPY file as stored: HxW or HxWxC, its own dtype, RGB order.");
  m.def("read_depth", [](const py::object& file, double scale) {
          return matToArray(readDepth(toPath(file, "file"), scale));
        }, py::arg("file"), py::arg("scale") = 0.0,
        "Depth in metres (float32, 0 = invalid); scale: metres per unit of an integer file.");
  m.def("read_normals", [](const py::object& file) { return matToArray(readNormals(toPath(file, "file"))); },
        py::arg("file"), "Unit normals HxWx3 float32, camera frame; (0,0,0) = invalid.");
  m.def("read_labels", [](const py::object& file) { return matToArray(readLabels(toPath(file, "file"))); },
        py::arg("file"), "A label map (instanceIds, labelIds, light ids) as int32.");
  m.def("write_image", [](const py::object& file, const py::array& image) {
          const py::array contiguous = py::module_::import("numpy").attr("ascontiguousarray")(image);
          writeImage(toPath(file, "file"), arrayToMat(contiguous, "image"));
        }, py::arg("file"), py::arg("image"), "Writes an array by extension (PNG, TIFF, EXR, PFM, NPY), atomically.");
  m.def("write_depth", [](const py::object& file, const py::array& depth, double scale) {
          const py::array contiguous = asArray(depth, py::dtype::of<float>());
          writeDepth(toPath(file, "file"), arrayToMat(contiguous, "depth"), scale);
        }, py::arg("file"), py::arg("depth"), py::arg("scale") = 1.0 / 256.0,
        "Writes metres (float32) by extension; a 16-bit PNG stores depth / scale.");
}

}  // namespace

void bindScene(py::module_& m) {
  bindSceneClass(m);
  bindReaders(m);
  m.def("default_scene", [] { return defaultScene().string(); }, "The embedded default scene's manifest.");
  m.def("data_directory", [] { return dataDirectory().string(); },
        "The bundled data: $SOLO_DATA_DIR, the source tree's data/ or the install prefix's.");
  m.def("load_scene", [](const py::object& manifest) {
          const std::filesystem::path file = manifest.is_none() ? defaultScene() : toPath(manifest, "manifest");
          auto p = std::make_shared<PyScene>();
          {
            const py::gil_scoped_release release;
            p->scene = loadScene(file);
          }
          return p;
        }, py::arg("manifest") = py::none(),
        "Reads a scene manifest and its maps (docs/scene-format.md); None: the embedded default scene.");
  m.def("scene_from_arrays",
        [](const py::object& image, const py::object& depth, const py::object& normals, const py::object& albedo,
           const py::object& roughness, const py::object& instances, const py::object& labels,
           const py::object& lights, const py::object& light_groups, const py::object& camera, double depth_scale,
           const std::string& name) {
          return sceneFromArrays(
              {image, depth, normals, albedo, roughness, instances, labels, lights, light_groups, camera, depth_scale, name});
        },
        py::arg("image"), py::arg("depth"), py::kw_only(), py::arg("normals") = py::none(),
        py::arg("albedo") = py::none(), py::arg("roughness") = py::none(), py::arg("instances") = py::none(),
        py::arg("labels") = py::none(), py::arg("lights") = py::none(), py::arg("light_groups") = py::none(),
        py::arg("camera") = py::none(), py::arg("depth_scale") = 0.0, py::arg("name") = "arrays",
        "A scene from arrays, converted and checked as load_scene converts and checks files (docs/python.md).");
}

}  // namespace solo::python
