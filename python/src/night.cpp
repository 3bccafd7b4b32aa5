// The night conversion: its options as keyword arguments named like `solo night`'s long options
// (dashes as underscores) over a preset, the conversion of a loaded scene with every picture it
// makes as numpy arrays, and the files-to-files job `solo night` runs.

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/lighting/light_record.h>
#include <solo/pipeline/night_conversion.h>
#include <solo/pipeline/night_job.h>
#include <solo/pipeline/night_presets.h>
#include <solo/post/colour_encoding.h>
#include <solo/post/night_statistics.h>
#include <solo/render/light_sampler.h>
#include <solo/render/sampler.h>

#include <pybind11/stl.h>

#include <atomic>
#include <fstream>
#include <map>
#include <set>
#include <unistd.h>

namespace solo::python {

namespace {

using O = NightConversionOptions;

// ---- options ----------------------------------------------------------------------------

/// One keyword argument of the night conversion: its name (`solo night`'s long option with
/// underscores) and how it reads and sets its field.
struct Knob {
  std::string name;
  std::function<py::object(O&)> get;
  std::function<void(O&, const py::handle&)> set;
};

template <typename T>
T castKnob(const py::handle& value, const std::string& name) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!py::isinstance<py::bool_>(value) && !py::hasattr(value, "dtype"))
      throw py::type_error(name + ": expected True or False");
  } else if constexpr (std::is_integral_v<T>) {
    if (py::isinstance<py::bool_>(value) || py::isinstance<py::float_>(value))
      throw py::type_error(name + ": expected a whole number");
  }
  try {
    return py::cast<T>(value);
  } catch (const py::cast_error&) {
    throw py::type_error(name + ": expected " + (std::is_same_v<T, bool> ? "True or False"
                                                 : std::is_integral_v<T> ? "a whole number"
                                                                         : "a number") +
                         ", got " + py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
}

template <typename T>
Knob valueKnob(const std::string& name, T& (*field)(O&)) {
  return {name, [field](O& o) -> py::object { return py::cast(field(o)); },
          [field, name](O& o, const py::handle& v) { field(o) = castKnob<T>(v, name); }};
}

template <typename Enum>
Knob choiceKnob(const std::string& name, const std::map<std::string, Enum>& names, Enum& (*field)(O&)) {
  return {name,
          [field, names](O& o) -> py::object {
            for (const auto& [text, value] : names)
              if (value == field(o)) return py::str(text);
            return py::none();
          },
          [field, names, name](O& o, const py::handle& v) {
            const std::string text = py::str(v);
            const auto it = names.find(text);
            if (it == names.end()) {
              std::string choices;
              for (const auto& entry : names) choices += (choices.empty() ? "" : ", ") + entry.first;
              throw InputError("--" + name, "unknown value \"" + text + "\" (use " + choices + ")");
            }
            field(o) = it->second;
          }};
}

/// The light record: a path, a record dict (written to a temporary file for the run), or None.
Knob lightRecordKnob() {
  return {"light_record",
          [](O& o) -> py::object { return o.light_record ? py::object(py::str(o.light_record->string())) : py::none(); },
          [](O& o, const py::handle& v) {
            if (v.is_none()) o.light_record.reset();
            else if (!py::isinstance<py::dict>(v)) o.light_record = toPath(v, "light_record");
            // A dict is written by the caller (NightArguments), which owns the file.
          }};
}

const std::vector<Knob>& knobs() {
  static const std::map<std::string, LightSamplerKind> kLightSamplers = {
      {"uniform", LightSamplerKind::Uniform}, {"power", LightSamplerKind::Power}, {"hierarchy", LightSamplerKind::Hierarchy}};
  static const std::map<std::string, SamplerKind> kSamplers = {{"sobol", SamplerKind::Sobol},
                                                               {"independent", SamplerKind::Independent}};
  static const std::vector<Knob> list = {
      valueKnob<std::uint64_t>("seed", +[](O& o) -> std::uint64_t& { return o.seed; }),
      valueKnob<double>("min_depth_share", +[](O& o) -> double& { return o.min_depth_share; }),
      valueKnob<bool>("refine", +[](O& o) -> bool& { return o.refine; }),
      valueKnob<bool>("complete", +[](O& o) -> bool& { return o.refinement.complete; }),
      valueKnob<bool>("optimize", +[](O& o) -> bool& { return o.refinement.optimize; }),
      valueKnob<int>("optimize_iterations", +[](O& o) -> int& { return o.refinement.optimization.max_iterations; }),
      valueKnob<double>("optimize_tolerance", +[](O& o) -> double& { return o.refinement.optimization.function_tolerance; }),
      valueKnob<bool>("solids", +[](O& o) -> bool& { return o.mesh.close_solids; }),
      valueKnob<bool>("backdrops", +[](O& o) -> bool& { return o.mesh.backdrops; }),
      valueKnob<bool>("evaluate_mesh", +[](O& o) -> bool& { return o.mesh.evaluate; }),
      valueKnob<bool>("ablation", +[](O& o) -> bool& { return o.lights.instantiation.ablation; }),
      lightRecordKnob(),
      valueKnob<bool>("headlights", +[](O& o) -> bool& { return o.night_scene.headlights; }),
      valueKnob<double>("headlight_flux", +[](O& o) -> double& { return o.night_scene.headlight_flux_lm; }),
      valueKnob<bool>("shading_normals", +[](O& o) -> bool& { return o.night_scene.shading_normals; }),
      valueKnob<bool>("remove_day_light", +[](O& o) -> bool& { return o.night_scene.remove_day_light; }),
      valueKnob<bool>("day_shadows_from_image", +[](O& o) -> bool& { return o.night_scene.day_light.shadows_from_image; }),
      choiceKnob<LightSamplerKind>("light_sampler", kLightSamplers, +[](O& o) -> LightSamplerKind& { return o.render.light_sampler; }),
      choiceKnob<SamplerKind>("sampler", kSamplers, +[](O& o) -> SamplerKind& { return o.render.sampler; }),
      valueKnob<int>("min_spp", +[](O& o) -> int& { return o.render.min_samples; }),
      valueKnob<int>("max_spp", +[](O& o) -> int& { return o.render.max_samples; }),
      valueKnob<double>("relative_error", +[](O& o) -> double& { return o.render.relative_error; }),
      valueKnob<bool>("noise_target", +[](O& o) -> bool& { return o.noise_target; }),
      valueKnob<double>("noise_factor", +[](O& o) -> double& { return o.render.noise_factor; }),
      valueKnob<double>("shadow_roulette", +[](O& o) -> double& { return o.render.shadow_roulette; }),
      valueKnob<int>("max_bounces", +[](O& o) -> int& { return o.render.max_bounces; }),
      valueKnob<float>("indirect_clamp", +[](O& o) -> float& { return o.render.indirect_clamp; }),
      valueKnob<int>("mesh_downsample", +[](O& o) -> int& { return o.mesh_downsample; }),
      valueKnob<int>("render_downsample", +[](O& o) -> int& { return o.render_downsample; }),
      valueKnob<bool>("pixel_texture", +[](O& o) -> bool& { return o.render.pixel_texture; }),
      valueKnob<bool>("upsample_texture", +[](O& o) -> bool& { return o.upsample.texture; }),
      valueKnob<bool>("denoise", +[](O& o) -> bool& { return o.denoise.enabled; }),
      valueKnob<bool>("glare", +[](O& o) -> bool& { return o.post.glare; }),
      valueKnob<bool>("noise", +[](O& o) -> bool& { return o.post.noise; }),
      valueKnob<double>("sensor_white", +[](O& o) -> double& { return o.sensor_white_cd_m2; }),
      valueKnob<double>("camera_f_number", +[](O& o) -> double& { return o.camera.f_number; }),
      valueKnob<double>("camera_max_shutter", +[](O& o) -> double& { return o.camera.max_shutter_s; }),
      valueKnob<double>("camera_max_iso", +[](O& o) -> double& { return o.camera.max_iso; }),
      valueKnob<double>("camera_compensation", +[](O& o) -> double& { return o.camera.compensation_ev; }),
      valueKnob<double>("noise_scale", +[](O& o) -> double& { return o.post.noise_options.std_scale; }),
      valueKnob<double>("white_clip", +[](O& o) -> double& { return o.post.encoding_options.white_clip; }),
      valueKnob<double>("knee_point", +[](O& o) -> double& { return o.post.encoding_options.knee_point; }),
      valueKnob<double>("glare_scatter", +[](O& o) -> double& { return o.post.glare_options.scatter_fraction; }),
      valueKnob<double>("glare_threshold", +[](O& o) -> double& { return o.post.glare_options.threshold; }),
  };
  return list;
}

/// `solo night`'s name of a knob: dashes for underscores.
std::string cliName(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (c == '_') c = '-';
  return out == "light-record" ? "lights" : out;
}

/// A light record dict written to a temporary file for one run, removed afterwards.
class TemporaryRecord {
 public:
  explicit TemporaryRecord(const py::handle& record) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("solo-light-record-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".json");
    std::ofstream out(path_);
    out << jsonDumps(record);
    if (!out) throw InputError(path_, "cannot write the light record for the run");
  }
  ~TemporaryRecord() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  TemporaryRecord(const TemporaryRecord&) = delete;
  TemporaryRecord& operator=(const TemporaryRecord&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// The options of one run: the preset with the given keyword arguments over it, checked.
struct NightArguments {
  O options;
  std::string preset;
  std::unique_ptr<TemporaryRecord> record;
};

NightArguments nightArguments(const std::string& preset, const py::dict& kwargs) {
  NightArguments a;
  a.preset = preset;
  std::set<std::string> given;
  for (const auto& item : kwargs) {
    const std::string name = py::str(item.first);
    const auto it = std::find_if(knobs().begin(), knobs().end(), [&](const Knob& k) { return k.name == name; });
    if (it == knobs().end())
      throw py::type_error("unexpected keyword argument '" + name + "' (solo.night_options() lists them)");
    it->set(a.options, item.second);
    if (name == "light_record" && py::isinstance<py::dict>(item.second)) {
      a.record = std::make_unique<TemporaryRecord>(item.second);
      a.options.light_record = a.record->path();
    }
    given.insert(cliName(name));
  }
  applyNightPreset(a.options, preset, [&given](const std::string& knob) { return given.count(knob) > 0; });
  validateNightConversionOptions(a.options);
  return a;
}

py::dict nightOptionsBinding(const std::string& preset, const py::kwargs& kwargs) {
  NightArguments a = nightArguments(preset, kwargs);
  if (a.record) a.options.light_record.reset();
  py::dict out;
  out["preset"] = preset;
  for (const Knob& k : knobs()) out[py::str(k.name)] = k.get(a.options);
  if (kwargs.contains("light_record")) out["light_record"] = kwargs["light_record"];
  return out;
}

// ---- the conversion ---------------------------------------------------------------------

/// The stages a job announces; a conversion of a loaded scene starts at "refine".
const std::vector<std::string> kJobStages = {"input", "refine", "mesh", "lights", "render", "denoise", "post"};
const std::vector<std::string> kConversionStages(kJobStages.begin() + 1, kJobStages.end());

NightConversionCallbacks callbacksOf(const Progress& progress, bool render_progress) {
  NightConversionCallbacks callbacks;
  callbacks.render_progress = render_progress;
  if (progress.enabled()) callbacks.stage_started = [&progress](const std::string& stage) { progress.stage(stage); };
  return callbacks;
}

/// What a conversion made, as arrays and dicts.
py::dict conversionToDict(NightConversionResult& r, const cv::Mat& image8, const NightStatistics& realism,
                          const RunReport& report, bool return_mesh) {
  py::dict out;
  out["image"] = matToArray(image8);
  out["encoded"] = matToArray(r.developed.encoded);
  out["linear_rgb"] = matToArray(r.developed.linear_rgb);
  out["render"] = matToArray(r.rendered.radiance);
  py::dict aovs;
  aovs["albedo"] = matToArray(r.rendered.albedo);
  aovs["normal"] = matToArray(r.rendered.normal);
  aovs["depth"] = matToArray(r.rendered.depth_m);
  aovs["light_id"] = matToArray(r.rendered.light_id);
  aovs["emitter_coverage"] = matToArray(r.rendered.emitter_coverage);
  aovs["samples"] = matToArray(r.rendered.samples);
  aovs["std_error"] = matToArray(r.rendered.std_error);
  out["aovs"] = aovs;
  out["refined_depth"] = matToArray(r.refined.depth_m);
  out["uncertain"] = matToArray(r.refined.uncertain);
  out["lights"] = jsonLoads(lightRecordJson(r.record));
  out["sensor_white_cd_m2"] = r.sensor_white_cd_m2;
  out["realism"] = nightStatisticsToDict(realism);
  out["report"] = reportToDict(report);
  if (return_mesh) {
    TriangleMesh mesh;
    {
      const py::gil_scoped_release release;
      mesh = toTriangleMesh(r.mesh.mesh);
    }
    out["mesh"] = meshToArrays(std::move(mesh));
  }
  return out;
}

py::dict convertNight(const PySceneHandle& scene, const std::string& preset, const py::object& callback,
                      bool render_progress, bool return_mesh, const py::kwargs& kwargs) {
  const NightArguments a = nightArguments(preset, kwargs);
  const Progress progress(callback, kConversionStages);
  const NightConversionCallbacks callbacks = callbacksOf(progress, render_progress);
  RunReport report;
  report.command = "night";
  report.scene = scene->scene.manifest.file.string();
  report.seed = a.options.seed;
  report.preset = preset;
  report.versions = pipelineDependencyVersions();
  NightConversionResult result;
  cv::Mat image8;
  NightStatistics realism;
  {
    const py::gil_scoped_release release;
    const Stopwatch total;
    report.stages.push_back(sceneInputReport(scene->scene, 0));
    result = runNightConversion(scene->scene, a.options, callbacks);
    for (const StageReport& stage : result.stages) report.stages.push_back(stage);
    const Stopwatch realism_clock;
    realism = computeNightStatistics(result.developed.encoded, ChannelOrder::Rgb);
    report.stages.push_back(nightStatisticsReport(realism, realism_clock.seconds()));
    image8 = quantiseEncoded(result.developed.encoded, 8);
    report.total_seconds = total.seconds();
  }
  progress.done();
  return conversionToDict(result, image8, realism, report, return_mesh);
}

py::dict nightJob(const py::object& scene, const py::object& output, const py::object& report_file,
                  const py::object& render_exr, bool sixteen_bit, const py::object& contact_sheet,
                  const std::string& preset, const py::object& callback, bool render_progress,
                  const py::kwargs& kwargs) {
  const NightArguments a = nightArguments(preset, kwargs);
  NightJobOptions job;
  job.scene = toOptionalPath(scene, "scene");
  job.output = toPath(output, "output");
  job.report = toOptionalPath(report_file, "report");
  job.render_exr = toOptionalPath(render_exr, "render_exr");
  job.sixteen_bit = sixteen_bit;
  job.contact_sheet = toOptionalPath(contact_sheet, "contact_sheet");
  job.preset = preset;
  const Progress progress(callback, kJobStages);
  const NightConversionCallbacks callbacks = callbacksOf(progress, render_progress);
  NightJobResult result;
  {
    const py::gil_scoped_release release;
    result = runNightJob(job, a.options, callbacks);
  }
  progress.done();
  return reportToDict(result.report);
}

}  // namespace

void bindNight(py::module_& m) {
  m.def("presets", [] { return nightPresetNames(); }, "The quality presets, fastest first (docs/presets.md).");
  m.def("night_options", &nightOptionsBinding, py::arg("preset") = "default",
        "Every keyword argument of convert_night and night with its value under `preset` and the given "
        "overrides, checked as the conversion checks them.");
  m.def("convert_night", &convertNight, py::arg("scene"), py::kw_only(), py::arg("preset") = "default",
        py::arg("progress") = py::none(), py::arg("render_progress") = false, py::arg("return_mesh") = false,
        "The night conversion of a loaded scene (refine, mesh, lights, render, denoise, post). Keyword "
        "arguments: `solo night`'s options with underscores (solo.night_options() lists them). Returns the "
        "night image (uint8), the encoded and linear images, the render and its AOVs, the refined depth, the "
        "light record, the realism statistics and the run report.");
  m.def("night", &nightJob, py::arg("scene") = py::none(), py::arg("output") = "night.png", py::kw_only(),
        py::arg("report") = py::none(), py::arg("render_exr") = py::none(), py::arg("sixteen_bit") = false,
        py::arg("contact_sheet") = py::none(), py::arg("preset") = "default", py::arg("progress") = py::none(),
        py::arg("render_progress") = false,
        "`solo night` from files to files: the scene manifest (None: the embedded default scene) to the night "
        "image, its report (default <output stem>.report.json) and on request the render with its AOVs and a "
        "contact sheet. A run that fails writes nothing. Returns the run report as a dict.");
}

}  // namespace solo::python
