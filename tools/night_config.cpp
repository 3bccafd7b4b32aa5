// `solo night --write-config`: the effective options as a config file (commands.h).

#include "commands.h"

#include <solo/core/error.h>
#include <solo/render/light_sampler.h>
#include <solo/render/sampler.h>

#include <charconv>
#include <sstream>

namespace solo::tools {

namespace {

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

std::string nightConfigText(const NightOptions& options) {
  const NightJobOptions& j = options.job;
  const NightConversionOptions& o = options.conversion;
  std::ostringstream out;
  const auto line = [&out](const std::string& key, const std::string& value) { out << key << " = " << value << "\n"; };
  const auto path = [&](const std::string& key, const std::filesystem::path& p) { line(key, quoted(key, p.string())); };
  const auto flag = [&](const std::string& key, bool value) { line(key, value ? "true" : "false"); };
  out << "# solo night configuration: solo night --config FILE (docs/presets.md).\n"
         "# Options given on the command line override these values.\n"
         "[night]\n";
  line("preset", quoted("preset", options.preset));
  if (j.scene) path("scene", *j.scene);
  path("output", j.output);
  if (j.report) path("report", *j.report);
  if (j.render_exr) path("render-exr", *j.render_exr);
  if (j.contact_sheet) path("contact-sheet", *j.contact_sheet);
  line("seed", std::to_string(o.seed));
  flag("16bit", j.sixteen_bit);
  flag("refine", o.refine);
  flag("complete", o.refinement.complete);
  line("min-depth-share", number(o.min_depth_share));
  flag("optimize", o.refinement.optimize);
  line("optimize-iterations", std::to_string(o.refinement.optimization.max_iterations));
  line("optimize-tolerance", number(o.refinement.optimization.function_tolerance));
  flag("solids", o.mesh.close_solids);
  flag("backdrops", o.mesh.backdrops);
  flag("evaluate-mesh", o.mesh.evaluate);
  flag("ablation", o.lights.instantiation.ablation);
  if (o.light_record) path("lights", *o.light_record);
  flag("propose-lights", o.propose_lights);
  flag("headlights", o.night_scene.headlights);
  flag("shading-normals", o.night_scene.shading_normals);
  flag("remove-day-light", o.night_scene.remove_day_light);
  flag("day-shadows-from-image", o.night_scene.day_light.shadows_from_image);
  line("headlight-flux", number(o.night_scene.headlight_flux_lm));
  line("light-sampler", quoted("light-sampler", lightSamplerName(o.render.light_sampler)));
  flag("near-field-lights", o.render.near_field_lights);
  line("sampler", quoted("sampler", samplerKindName(o.render.sampler)));
  line("min-spp", std::to_string(o.render.min_samples));
  line("max-spp", std::to_string(o.render.max_samples));
  line("relative-error", number(o.render.relative_error));
  flag("noise-target", o.noise_target);
  line("noise-factor", number(o.render.noise_factor));
  line("shadow-roulette", number(o.render.shadow_roulette));
  line("max-bounces", std::to_string(o.render.max_bounces));
  line("indirect-clamp", number(o.render.indirect_clamp));
  line("mesh-downsample", std::to_string(o.mesh_downsample));
  line("render-downsample", std::to_string(o.render_downsample));
  flag("pixel-texture", o.render.pixel_texture);
  flag("upsample-texture", o.upsample.texture);
  flag("denoise", o.denoise.enabled);
  line("firefly-sigma", number(o.denoise.firefly_sigma));
  line("denoise-passes", std::to_string(o.denoise.iterations));
  line("denoise-fine-passes", std::to_string(o.denoise.fine_passes));
  flag("glare", o.post.glare);
  flag("noise", o.post.noise);
  line("sensor-white", number(o.sensor_white_cd_m2));
  line("camera-f-number", number(o.camera.f_number));
  line("camera-max-shutter", number(o.camera.max_shutter_s));
  line("camera-max-iso", number(o.camera.max_iso));
  line("camera-compensation", number(o.camera.compensation_ev));
  line("noise-scale", number(o.post.noise_options.std_scale));
  line("chroma-denoise", number(o.post.noise_options.chroma_denoise_sigma_px));
  line("glare-scatter", number(o.post.glare_options.scatter_fraction));
  line("white-clip", number(o.post.encoding_options.white_clip));
  line("knee-point", number(o.post.encoding_options.knee_point));
  line("glare-threshold", number(o.post.glare_options.threshold));
  return out.str();
}

}  // namespace solo::tools
