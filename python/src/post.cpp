// The camera-like post-process of a linear XYZ render as `solo post` runs it (docs/post-processing.md),
// and the night-photo statistics of an image (`solo eval night`, docs/evaluation.md).

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/night_statistics.h>
#include <solo/post/post_process.h>

#include <pybind11/stl.h>

#include <map>

namespace solo::python {

namespace {

template <typename Enum>
Enum named(const std::map<std::string, Enum>& names, const std::string& text, const std::string& option) {
  const auto it = names.find(text);
  if (it != names.end()) return it->second;
  std::string choices;
  for (const auto& entry : names) choices += (choices.empty() ? "" : ", ") + entry.first;
  throw InputError(option, "unknown value \"" + text + "\" (use " + choices + ")");
}

const std::map<std::string, GlareMethod> kGlareMethods = {{"auto", GlareMethod::Automatic},
                                                          {"direct", GlareMethod::Direct},
                                                          {"fft", GlareMethod::Fft},
                                                          {"tiled", GlareMethod::TiledFft}};
const std::map<std::string, TransferCurve> kTransferCurves = {
    {"gamma2.2", TransferCurve::Gamma22}, {"srgb", TransferCurve::Srgb}, {"linear", TransferCurve::Linear}};
const std::map<std::string, NegativeHandling> kNegatives = {{"desaturate", NegativeHandling::Desaturate},
                                                            {"clip", NegativeHandling::Clip}};
const std::map<std::string, HighlightHandling> kHighlights = {{"desaturate", HighlightHandling::Desaturate},
                                                              {"clip", HighlightHandling::Clip}};

/// `solo post`'s flags, named alike.
struct PostArguments {
  double stops;
  std::optional<double> shutter, f_number;
  double iso;
  bool glare;
  double glare_threshold;
  int glare_size;
  std::string glare_method;
  bool noise;
  double noise_scale;
  bool demosaic;
  double chroma_denoise, chroma_denoise_strength;
  std::uint64_t seed;
  bool adaptation;
  std::string curve, negatives, highlights;
  double highlight_knee, white_clip, knee_point, glare_scatter;
};

/// The options as `solo post` sets them: --shutter or --f-number make a camera (ISO 3200, 1/30 s,
/// f/2 for the other values) whose ISO is --iso.
PostProcessOptions postOptions(const PostArguments& a) {
  PostProcessOptions o;
  o.exposure_options.stops = a.stops;
  if (a.shutter || a.f_number) {
    CameraExposure camera;
    if (a.shutter) camera.shutter_s = *a.shutter;
    if (a.f_number) camera.f_number = *a.f_number;
    o.exposure_options.camera = camera;
  }
  o.noise_options.iso = a.iso;
  if (o.exposure_options.camera) o.exposure_options.camera->iso = a.iso;
  o.glare = a.glare;
  o.glare_options.threshold = a.glare_threshold;
  o.glare_options.size = a.glare_size;
  o.glare_options.method = named(kGlareMethods, a.glare_method, "--glare-method");
  o.glare_options.scatter_fraction = a.glare_scatter;
  o.noise = a.noise;
  o.noise_options.std_scale = a.noise_scale;
  o.noise_options.demosaic = a.demosaic;
  o.noise_options.chroma_denoise_sigma_px = a.chroma_denoise;
  o.noise_options.chroma_denoise_strength = a.chroma_denoise_strength;
  o.noise_options.seed = a.seed;
  o.adaptation = a.adaptation;
  o.encoding_options.curve = named(kTransferCurves, a.curve, "--curve");
  o.encoding_options.negatives = named(kNegatives, a.negatives, "--negatives");
  o.encoding_options.highlights = named(kHighlights, a.highlights, "--highlights");
  o.encoding_options.highlight_knee = a.highlight_knee;
  o.encoding_options.white_clip = a.white_clip;
  o.encoding_options.knee_point = a.knee_point;
  return o;
}

py::dict postProcessBinding(const py::object& xyz, const PostArguments& arguments) {
  const PostProcessOptions options = postOptions(arguments);
  validatePostProcessOptions(options);
  const py::array array = asArray(xyz, py::dtype::of<float>());
  const cv::Mat xyz_e = arrayToMat(array, "xyz");
  if (xyz_e.channels() != 3) throw py::value_error("xyz: expected an HxWx3 array (X, Y, Z), got " +
                                                   std::to_string(xyz_e.channels()) + " channels");
  RunReport report;
  report.command = "post";
  report.seed = options.noise_options.seed;
  report.scene = "array";
  PostProcessResult result;
  cv::Mat image8;
  {
    const py::gil_scoped_release release;
    const Stopwatch total;
    result = postProcess(xyz_e, options);
    image8 = quantiseEncoded(result.encoded, 8);
    for (StageReport& step : result.steps) report.stages.push_back(std::move(step));
    report.total_seconds = total.seconds();
  }
  py::dict out;
  out["image"] = matToArray(image8);
  out["encoded"] = matToArray(result.encoded);
  out["linear_rgb"] = matToArray(result.linear_rgb);
  out["report"] = reportToDict(report);
  return out;
}

}  // namespace

void bindPost(py::module_& m) {
  const PostProcessOptions d;  // the library's defaults are the arguments' defaults
  m.def(
      "post_process",
      [](const py::object& xyz, double stops, std::optional<double> shutter, std::optional<double> f_number, double iso,
         bool glare, double glare_threshold, int glare_size, const std::string& glare_method, bool noise,
         double noise_scale, bool demosaic, double chroma_denoise, double chroma_denoise_strength, std::uint64_t seed,
         bool adaptation, const std::string& curve, const std::string& negatives, const std::string& highlights,
         double highlight_knee, double white_clip, double knee_point, double glare_scatter) {
        return postProcessBinding(xyz, {stops, shutter, f_number, iso, glare, glare_threshold, glare_size, glare_method,
                                        noise, noise_scale, demosaic, chroma_denoise, chroma_denoise_strength, seed,
                                        adaptation, curve, negatives, highlights, highlight_knee, white_clip,
                                        knee_point, glare_scatter});
      },
      py::arg("xyz"), py::kw_only(), py::arg("stops") = d.exposure_options.stops, py::arg("shutter") = py::none(),
      py::arg("f_number") = py::none(), py::arg("iso") = d.noise_options.iso, py::arg("glare") = d.glare,
      py::arg("glare_threshold") = d.glare_options.threshold, py::arg("glare_size") = d.glare_options.size,
      py::arg("glare_method") = "auto", py::arg("noise") = d.noise, py::arg("noise_scale") = d.noise_options.std_scale,
      py::arg("demosaic") = d.noise_options.demosaic,
      py::arg("chroma_denoise") = d.noise_options.chroma_denoise_sigma_px,
      py::arg("chroma_denoise_strength") = d.noise_options.chroma_denoise_strength,
      py::arg("seed") = d.noise_options.seed, py::arg("adaptation") = d.adaptation, py::arg("curve") = "gamma2.2",
      py::arg("negatives") = "desaturate", py::arg("highlights") = "desaturate",
      py::arg("highlight_knee") = d.encoding_options.highlight_knee,
      py::arg("white_clip") = d.encoding_options.white_clip, py::arg("knee_point") = d.encoding_options.knee_point,
      py::arg("glare_scatter") = d.glare_options.scatter_fraction,
      "The post-process of `solo post` on a linear XYZ render relative to white E (HxWx3): glare, exposure, "
      "sensor noise, Bradford adaptation, sRGB encoding, chroma noise reduction of the encoded noise. Returns "
      "{image uint8, encoded, linear_rgb, report}.");
  m.def("night_statistics", [](const py::object& image) {
          const py::array array = py::module_::import("numpy").attr("ascontiguousarray")(image);
          const cv::Mat mat = arrayToMat(array, "image");
          NightStatistics s;
          {
            const py::gil_scoped_release release;
            s = computeNightStatistics(mat, ChannelOrder::Rgb);
          }
          return nightStatisticsToDict(s);
        }, py::arg("image"),
        "The realism statistics of a night image (HxWx3 RGB uint8, uint16 or float in [0, 1]), as `solo eval "
        "night` measures a file (docs/evaluation.md).");
}

}  // namespace solo::python
