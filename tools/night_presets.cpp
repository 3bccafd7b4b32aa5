// Quality presets of `solo night` (the table below; measured times and accuracy in
// docs/presets.md) and the writer of its configuration file.

#include "night_presets.h"

#include <solo/core/error.h>

#include <array>
#include <charconv>
#include <sstream>

namespace solo::tools {

namespace {

// The knobs a preset sets. `default` is exactly NightOptions' defaults (a run without
// --preset is unchanged); draft and final were chosen by measurement (docs/presets.md).
struct PresetValues {
  int min_spp, max_spp;          // per pixel
  double relative_error;         // adaptive sampling target
  const char* light_sampler;
  bool optimize;                 // normal-guided depth optimisation
  int optimize_iterations;
  double optimize_tolerance;
  bool evaluate_mesh;            // self-intersection and manifoldness counts
  bool glare, noise;
  bool noise_target;    // adaptive sampling to the sensor noise instead of relative_error
  double noise_factor;  // render noise allowed, fraction of the sensor noise sigma
  double shadow_roulette;  // shadow-ray roulette below this fraction of the sensor noise at black
  int max_bounces;
  int mesh_downsample;    // mesh from the depth downsampled by this factor
  int render_downsample;  // render at the image size divided by this factor
  bool denoise;           // edge-aware filter of the render (render_denoise.h)
};

//                                spp     rel.err sampler  opt   iter  tol   eval   glare noise  n.target factor
//                                roulette bounces mesh/ render/ denoise
constexpr PresetValues kDraft = {1, 2, 0.3, "power", true, 3, 1e-6, false, true, true, false, 1, 0.3, 12, 2, 2, true};
constexpr PresetValues kDefault = {2, 8, 0.1, "power", true, 10, 1e-9, false, true, true, true, 1, 0.3, 12, 1, 1, true};
constexpr PresetValues kFinal = {8, 64, 0.03, "power", true, 10, 1e-9, true, true, true, true, 0.5, 0.3, 12, 1, 1, false};

struct Knob {
  const char* flag;
  void (*set)(NightOptions&, const PresetValues&);
};

// Every knob names its command-line flag: a knob the user gave keeps the user's value.
const std::array<Knob, 17> kKnobs = {{
    {"--min-spp", [](NightOptions& o, const PresetValues& p) { o.min_samples = p.min_spp; }},
    {"--max-spp", [](NightOptions& o, const PresetValues& p) { o.max_samples = p.max_spp; }},
    {"--relative-error", [](NightOptions& o, const PresetValues& p) { o.relative_error = p.relative_error; }},
    {"--light-sampler", [](NightOptions& o, const PresetValues& p) { o.light_sampler = p.light_sampler; }},
    {"--optimize", [](NightOptions& o, const PresetValues& p) { o.optimize = p.optimize; }},
    {"--optimize-iterations",
     [](NightOptions& o, const PresetValues& p) { o.optimize_iterations = p.optimize_iterations; }},
    {"--optimize-tolerance",
     [](NightOptions& o, const PresetValues& p) { o.optimize_tolerance = p.optimize_tolerance; }},
    {"--evaluate-mesh", [](NightOptions& o, const PresetValues& p) { o.evaluate_mesh = p.evaluate_mesh; }},
    {"--glare", [](NightOptions& o, const PresetValues& p) { o.glare = p.glare; }},
    {"--noise", [](NightOptions& o, const PresetValues& p) { o.noise = p.noise; }},
    {"--noise-target", [](NightOptions& o, const PresetValues& p) { o.noise_target = p.noise_target; }},
    {"--noise-factor", [](NightOptions& o, const PresetValues& p) { o.noise_factor = p.noise_factor; }},
    {"--shadow-roulette", [](NightOptions& o, const PresetValues& p) { o.shadow_roulette = p.shadow_roulette; }},
    {"--max-bounces", [](NightOptions& o, const PresetValues& p) { o.max_bounces = p.max_bounces; }},
    {"--mesh-downsample", [](NightOptions& o, const PresetValues& p) { o.mesh_downsample = p.mesh_downsample; }},
    {"--render-downsample", [](NightOptions& o, const PresetValues& p) { o.render_downsample = p.render_downsample; }},
    {"--denoise", [](NightOptions& o, const PresetValues& p) { o.denoise = p.denoise; }},
}};

const PresetValues& presetValues(const std::string& name) {
  if (name == "draft") return kDraft;
  if (name == "default") return kDefault;
  if (name == "final") return kFinal;
  throw InputError("--preset", "unknown preset \"" + name + "\" (use draft, default or final)");
}

std::string number(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  std::string text(buffer, end);
  // TOML floats need a fraction or an exponent; CLI11 reads either, people expect 1.0.
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

std::string quoted(const std::string& key, const std::string& text) {
  if (text.find('"') == std::string::npos) return '"' + text + '"';
  if (text.find('\'') == std::string::npos) return '\'' + text + '\'';
  throw InputError(text, "--" + key + ": a path with both quote characters cannot be written to a config file");
}

}  // namespace

const std::vector<std::string>& nightPresetNames() {
  static const std::vector<std::string> names = {"draft", "default", "final"};
  return names;
}

void applyNightPreset(NightOptions& options, const std::function<bool(const std::string& flag)>& given) {
  const PresetValues& values = presetValues(options.preset);
  for (const Knob& knob : kKnobs)
    if (!given(knob.flag)) knob.set(options, values);
}

std::string nightConfigText(const NightOptions& o) {
  std::ostringstream out;
  const auto line = [&out](const std::string& key, const std::string& value) { out << key << " = " << value << "\n"; };
  const auto path = [&](const std::string& key, const std::filesystem::path& p) { line(key, quoted(key, p.string())); };
  const auto flag = [&](const std::string& key, bool value) { line(key, value ? "true" : "false"); };
  out << "# solo night configuration: solo night --config FILE (docs/presets.md).\n"
         "# Options given on the command line override these values.\n"
         "[night]\n";
  line("preset", quoted("preset", o.preset));
  if (o.scene) path("scene", *o.scene);
  path("output", o.output);
  if (o.report) path("report", *o.report);
  if (o.render_exr) path("render-exr", *o.render_exr);
  if (o.contact_sheet) path("contact-sheet", *o.contact_sheet);
  line("seed", std::to_string(o.seed));
  flag("16bit", o.sixteen_bit);
  flag("refine", o.refine);
  flag("optimize", o.optimize);
  line("optimize-iterations", std::to_string(o.optimize_iterations));
  line("optimize-tolerance", number(o.optimize_tolerance));
  flag("solids", o.solids);
  flag("backdrops", o.backdrops);
  flag("evaluate-mesh", o.evaluate_mesh);
  flag("ablation", o.ablation);
  if (o.lights_record) path("lights", *o.lights_record);
  flag("headlights", o.headlights);
  line("headlight-flux", number(o.headlight_flux_lm));
  line("light-sampler", quoted("light-sampler", o.light_sampler));
  line("sampler", quoted("sampler", o.sampler));
  line("min-spp", std::to_string(o.min_samples));
  line("max-spp", std::to_string(o.max_samples));
  line("relative-error", number(o.relative_error));
  flag("noise-target", o.noise_target);
  line("noise-factor", number(o.noise_factor));
  line("shadow-roulette", number(o.shadow_roulette));
  line("max-bounces", std::to_string(o.max_bounces));
  line("indirect-clamp", number(o.indirect_clamp_cd_m2));
  line("mesh-downsample", std::to_string(o.mesh_downsample));
  line("render-downsample", std::to_string(o.render_downsample));
  flag("denoise", o.denoise);
  flag("glare", o.glare);
  flag("noise", o.noise);
  line("sensor-white", number(o.sensor_white_cd_m2));
  line("camera-f-number", number(o.camera_f_number));
  line("camera-max-shutter", number(o.camera_max_shutter_s));
  line("camera-max-iso", number(o.camera_max_iso));
  line("camera-compensation", number(o.camera_compensation_ev));
  line("noise-scale", number(o.noise_scale));
  line("glare-scatter", number(o.glare_scatter));
  line("white-clip", number(o.white_clip));
  line("knee-point", number(o.knee_point));
  line("glare-threshold", number(o.glare_threshold));
  return out.str();
}

}  // namespace solo::tools
