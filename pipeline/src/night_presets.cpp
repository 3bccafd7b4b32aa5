// Quality presets of the night conversion (the table below; measured times and accuracy in
// docs/presets.md).

#include <solo/pipeline/night_presets.h>

#include <solo/core/error.h>

#include <array>

namespace solo {

namespace {
// The knobs a preset sets. `default` is exactly NightConversionOptions' defaults (a run without
// --preset is unchanged); draft and final were chosen by measurement (docs/presets.md).
struct PresetValues {
  int min_spp, max_spp;          // per pixel
  double relative_error;         // adaptive sampling target
  LightSamplerKind light_sampler;
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
constexpr PresetValues kDraft = {1, 2, 0.3, LightSamplerKind::Power, true, 3, 1e-6, false, true, true, false, 1, 0.3, 12, 2, 2, true};
constexpr PresetValues kDefault = {2, 4, 0.1, LightSamplerKind::Power, true, 10, 1e-9, false, true, true, true, 1, 0.3, 12, kAutoDownsample, kAutoDownsample, true};
constexpr PresetValues kFinal = {8, 64, 0.03, LightSamplerKind::Hierarchy, true, 10, 1e-9, true, true, true, true, 0.5, 0.3, 12, 1, 1, true};

struct Knob {
  const char* name;  // solo night's long option without dashes
  void (*set)(NightConversionOptions&, const PresetValues&);
};

using O = NightConversionOptions;
using P = PresetValues;

// Every knob is named: a knob the user gave keeps the user's value.
const std::array<Knob, 17> kKnobs = {{
    {"min-spp", [](O& o, const P& p) { o.render.min_samples = p.min_spp; }},
    {"max-spp", [](O& o, const P& p) { o.render.max_samples = p.max_spp; }},
    {"relative-error", [](O& o, const P& p) { o.render.relative_error = p.relative_error; }},
    {"light-sampler", [](O& o, const P& p) { o.render.light_sampler = p.light_sampler; }},
    {"optimize", [](O& o, const P& p) { o.refinement.optimize = p.optimize; }},
    {"optimize-iterations", [](O& o, const P& p) { o.refinement.optimization.max_iterations = p.optimize_iterations; }},
    {"optimize-tolerance",
     [](O& o, const P& p) { o.refinement.optimization.function_tolerance = p.optimize_tolerance; }},
    {"evaluate-mesh", [](O& o, const P& p) { o.mesh.evaluate = p.evaluate_mesh; }},
    {"glare", [](O& o, const P& p) { o.post.glare = p.glare; }},
    {"noise", [](O& o, const P& p) { o.post.noise = p.noise; }},
    {"noise-target", [](O& o, const P& p) { o.noise_target = p.noise_target; }},
    {"noise-factor", [](O& o, const P& p) { o.render.noise_factor = p.noise_factor; }},
    {"shadow-roulette", [](O& o, const P& p) { o.render.shadow_roulette = p.shadow_roulette; }},
    {"max-bounces", [](O& o, const P& p) { o.render.max_bounces = p.max_bounces; }},
    {"mesh-downsample", [](O& o, const P& p) { o.mesh_downsample = p.mesh_downsample; }},
    {"render-downsample", [](O& o, const P& p) { o.render_downsample = p.render_downsample; }},
    {"denoise", [](O& o, const P& p) { o.denoise.enabled = p.denoise; }},
}};

const PresetValues& presetValues(const std::string& name) {
  if (name == "draft") return kDraft;
  if (name == "default") return kDefault;
  if (name == "final") return kFinal;
  throw InputError("--preset", "unknown preset \"" + name + "\" (use draft, default or final)");
}

}  // namespace

const std::vector<std::string>& nightPresetNames() {
  static const std::vector<std::string> names = {"draft", "default", "final"};
  return names;
}

const std::vector<std::string>& nightPresetKnobs() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    out.reserve(kKnobs.size());
    for (const Knob& knob : kKnobs) out.push_back(knob.name);
    return out;
  }();
  return names;
}

void applyNightPreset(NightConversionOptions& options, const std::string& preset,
                      const std::function<bool(const std::string& knob)>& keep) {
  const PresetValues& values = presetValues(preset);
  for (const Knob& knob : kKnobs)
    if (!keep || !keep(knob.name)) knob.set(options, values);
}

NightConversionOptions nightPreset(const std::string& preset) {
  NightConversionOptions options;
  applyNightPreset(options, preset);
  return options;
}

}  // namespace solo
