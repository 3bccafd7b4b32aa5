// Exports a scene solo renders to files Blender's Cycles can render (render_cycles.py), renders it
// with solo (a converged reference and the runs to compare), and compares any render with the
// reference. Benchmark tool only: neither the tests nor `solo night` need it or Blender.
//
//   export_blender_scene export SCENE OUT_DIR [WIDTHxHEIGHT] [REFERENCE_SPP] [SAMPLERS]
//       SCENE: night (the bench_render street: ~300 lights, 2 headlights), plane-area (a grey
//       plane under one rectangle light), plane-emitter (a grey plane under an emitting quad),
//       pipeline:MANIFEST (the render scene `solo night` builds from a scene manifest, e.g. of
//       `solo synth --seed 3 --size 1920x1080`: refined depth, cleaned mesh with solids, the
//       light record drawn with seed 3, the two headlights; the camera scaled to WIDTHxHEIGHT);
//       rough:MANIFEST (the same with its roughness map: solo only), windows:MANIFEST (without
//       the street lights), headlights:MANIFEST (no emitter but the two headlights).
//       Writes OUT_DIR/scene.json + *.f32/*.u32 arrays (camera frame = OpenCV, metres; colours
//       are XYZ relative to E, rendered channel by channel, so Cycles receives them as "RGB"
//       and no colour transform may touch them), solo_reference.exr, emitter_mask.exr (1 where any
//       reference sample's camera ray hits an emitter; those pixels and the image's outermost
//       rows and columns are left out of every error), solo_runs.csv (fixed sample counts and the default adaptive
//       settings: wall and CPU seconds, relative RMSE; each image as solo_<settings>.exr) for
//       each per-sample sampler in SAMPLERS ("sobol,independent" by default; "sobol" alone
//       halves the time). Prints the reference's own noise from its per-pixel standard errors.
//   export_blender_scene runs SCENE OUT_DIR [WIDTHxHEIGHT] [-] [SAMPLERS] [nee]
//       The solo runs again against the reference already in OUT_DIR (solo_runs_again.csv); the
//       exported scene files stay as they are. With `nee` (either command), also the
//       next-event-estimation A/B at 16 and 64 spp with the first sampler: emitters sampled by
//       area instead of solid angle, one shadow ray per light instead of one per vertex, and
//       both together; with `clamp` the indirect clamp at 30 to 3000 cd/m^2;
//       with `roulette` Russian roulette from bounce 1, 2 and 4 (the default is 3); with `split`
//       emission splitting (PathTracerOptions::emission_splits) 4 and 8 within 0.5 and 2 m.
//       With `adaptive`, only the default adaptive run and fixed sampling at its mean
//       samples per pixel.
//       The runs take the seed from the environment variable SOLO_SEED (7 unless set), so that a
//       firefly-ruled error can be averaged over seeds.
//   export_blender_scene error-sources SCENE OUT_DIR [WIDTHxHEIGHT] [REFERENCE_SPP] [SPP] [SEEDS] [ADAPTIVE_SEEDS]
//       Where solo's error comes from (docs/rendering.md, "Where the error comes from"): a
//       reference of each light component (PathComponent Direct and Indirect, REFERENCE_SPP Sobol
//       spp, 1024 by default, seed 1000; kept in OUT_DIR and reused), solo's SPP-spp image (16 by
//       default) of each, the same paths for both, and the default adaptive settings' image (the
//       whole light only), for SEEDS (8) and ADAPTIVE_SEEDS (2) seeds from SOLO_SEED (7 unless
//       set) on, their squared errors pooled. Prints the shares of the squared error of Y on the
//       pixels that see no emitter: direct, indirect, their cross term, and the worst 0.1 % of
//       each image's pixels (fireflies); the last line, `row: ...`, is the table's row. The first
//       seed's fixed images are written as error_fixed_direct.exr and error_fixed_indirect.exr,
//       to locate the pixels that carry the error.
//   Every command: SOLO_NEAR_FIELD=0 renders without near-field light selection.
//   export_blender_scene compare OUT_DIR IMAGE.exr
//       Relative RMSE of IMAGE's Y (second channel) against the reference on the pixels where no
//       emitter is seen and off the image's border (`counted`), the ratio of their means there,
//       the share of the squared error in the worst 1 % of those pixels, the three worst pixels,
//       and the error without the pixels within 1 and 2 pixels of a seen emitter.
//
// Differences from the production scene, so both renderers solve the same problem: every emitter
// is uniform (Cycles has no g(v, n) profile), the headlights emit over the full hemisphere (solo
// cuts at its spread angle, Cycles' spread falls off smoothly), Lambertian diffuse (Cycles'
// Diffuse BSDF at roughness 0), no roughness map (no specular lobe), black sky; and in the
// commands that pair with Cycles (export, runs, probe) no shading normals: every face shades with
// its geometric normal. Cycles bends a shading normal toward the geometric one wherever its
// mirror direction would fall below the surface, which on the grazing road and far facades
// changes the shading: with the normals handed to Cycles per face, the headlights-only image
// stayed 6 % darker than solo's (mean ratio 0.938), without them both agree (0.999 at 512
// samples, the border left out as `counted` says). error-sources keeps the scene as `solo night`
// renders it.

#include "../night_street.h"
#include "../pipeline_scene.h"

#include <solo/core/image_io.h>
#include <solo/core/report.h>
#include <solo/core/scene.h>
#include <solo/lighting/light_category.h>
#include <solo/render/night_scene.h>
#include <solo/render/path_tracer.h>
#include <solo/synth/street_scene.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <sys/resource.h>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;

namespace {

// Uniform emitters (Cycles has no g profile) and headlights over the whole hemisphere (Cycles
// fades a spot light's edge where solo cuts a hard cone).
solo::RenderScene nightStreet(int width, int height) {
  return solo::bench::nightStreet({width, height, /*profiled_emitters=*/false, /*headlight_spread_rad=*/3.14159265f});
}

// The scene `solo night` renders for `manifest` (pipeline_scene.h), with the comparison's
// simplifications: every emitter uniform, headlights over the hemisphere, no roughness (diffuse
// only), black sky.
solo::RenderScene pipelineScene(const fs::path& manifest, int width, int height) {
  solo::RenderScene scene = solo::bench::pipelineScene(manifest, width, height);
  for (auto& emitter : scene.emitters) emitter.profile = solo::EmitterProfile::Uniform;
  for (auto& light : scene.rectangle_lights) light.spread_rad = 3.14159265f;
  scene.face_roughness.clear();
  scene.sky_radiance = Eigen::Vector3f::Zero();
  scene.sky_zenith_radiance.reset();
  return scene;
}

// The scene kinds the scene-kind benchmark derives from a manifest (run_scene_kinds.sh): the
// comparison's pipeline scene (`pipeline:`), the same keeping the roughness map (`rough:`, Lambert
// + GGX, solo only: the Cycles script renders diffuse only), without the street lights
// (`windows:`: the windows and the cars' lights stay), and with no emitter at all but the two
// headlights (`headlights:`). A dropped emitter's faces keep their reflectance.
solo::RenderScene sceneKind(const std::string& name, int width, int height) {
  const auto manifest = [&](const char* prefix) { return name.substr(std::string(prefix).size()); };
  if (name.rfind("pipeline:", 0) == 0) return pipelineScene(manifest("pipeline:"), width, height);
  if (name.rfind("rough:", 0) == 0) {
    solo::RenderScene scene = solo::bench::pipelineScene(manifest("rough:"), width, height);
    for (auto& emitter : scene.emitters) emitter.profile = solo::EmitterProfile::Uniform;
    for (auto& light : scene.rectangle_lights) light.spread_rad = 3.14159265f;
    scene.sky_radiance = Eigen::Vector3f::Zero();
    scene.sky_zenith_radiance.reset();
    return scene;
  }
  const bool windows = name.rfind("windows:", 0) == 0, headlights = name.rfind("headlights:", 0) == 0;
  if (!windows && !headlights) throw std::runtime_error("unknown scene " + name);
  solo::RenderScene scene = pipelineScene(manifest(windows ? "windows:" : "headlights:"), width, height);
  std::size_t kept = 0;
  std::set<int> emitters_kept;
  for (int& emitter : scene.face_emitter) {
    if (emitter < 0) continue;
    const int category = solo::lightCategoryOfId(scene.emitters[static_cast<std::size_t>(emitter)].light_id);
    const bool street_light = category == static_cast<int>(solo::LightCategory::StreetLightHighCct) ||
                              category == static_cast<int>(solo::LightCategory::StreetLightLowCct);
    if (headlights || street_light) {
      emitter = -1;
    } else {
      ++kept;
      emitters_kept.insert(emitter);
    }
  }
  std::printf("%s: %zu emitters (%zu emitting triangles) kept\n", name.c_str(), emitters_kept.size(), kept);
  return scene;
}

// Adds the quad centre +- u/2 +- v/2 (two triangles, normal along u x v) to the scene.
void addQuad(solo::RenderScene& scene, const Eigen::Vector3f& centre, const Eigen::Vector3f& u,
             const Eigen::Vector3f& v, const Eigen::Vector3f& reflectance, int emitter) {
  const auto base = static_cast<std::uint32_t>(scene.vertices.size());
  scene.vertices.push_back(centre - 0.5f * u - 0.5f * v);
  scene.vertices.push_back(centre + 0.5f * u - 0.5f * v);
  scene.vertices.push_back(centre + 0.5f * u + 0.5f * v);
  scene.vertices.push_back(centre - 0.5f * u + 0.5f * v);
  scene.faces.push_back({base, base + 1, base + 2});
  scene.faces.push_back({base, base + 2, base + 3});
  for (int i = 0; i < 2; ++i) {
    scene.face_reflectance.push_back(reflectance);
    scene.face_emitter.push_back(emitter);
  }
}

// A grey plane 4 m ahead of the camera filling the view, facing it, lit from the upper left by a
// 1 m x 0.5 m rectangle light (plane-area) or an emitting quad of the same size (plane-emitter)
// 1.5 m in front of the plane.
solo::RenderScene litPlane(int width, int height, bool mesh_emitter) {
  solo::RenderScene scene;
  scene.camera = solo::PinholeCamera::acdc().scaledTo(width, height);
  addQuad(scene, {0.f, 0.f, 4.f}, {-12.f, 0.f, 0.f}, {0.f, 8.f, 0.f}, Eigen::Vector3f(0.5f, 0.5f, 0.5f), -1);
  const Eigen::Vector3f centre(-0.8f, -0.6f, 2.5f);
  const Eigen::Vector3f normal = (Eigen::Vector3f(0.f, 0.f, 4.f) - centre).normalized();
  const Eigen::Vector3f u = Eigen::Vector3f::UnitY().cross(normal).normalized();
  const Eigen::Vector3f v = normal.cross(u).normalized();
  const Eigen::Vector3f radiance(9.f, 10.f, 7.f);
  if (mesh_emitter) {
    scene.emitters.push_back({radiance, solo::EmitterProfile::Uniform, 0.f, 1});
    // Seen edge-on from the camera? No: it faces the plane, the camera sees its back (both sides emit).
    addQuad(scene, centre, v * 0.5f, u * 1.0f, Eigen::Vector3f(0.f, 0.f, 0.f), 0);
  } else {
    solo::RectangleLight light;
    light.centre = centre;
    light.normal = normal;
    light.edge_u = u * 1.0f;
    light.edge_v = v * 0.5f;
    light.radiance = radiance;
    light.spread_rad = 3.14159265f;
    scene.rectangle_lights.push_back(light);
  }
  return scene;
}

// CPU seconds of this process, every thread: on a shared machine a fairer cost than wall time
// (a render that gets half the cores for twice as long costs the same).
// SOLO_NEAR_FIELD=0 turns near-field light selection off (PathTracerOptions::near_field_lights),
// for comparing with and without it.
void applyNearFieldSetting(solo::PathTracerOptions& options) {
  if (const char* v = std::getenv("SOLO_NEAR_FIELD")) options.near_field_lights = std::atoi(v) != 0;
}

double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

template <typename T>
void writeArray(const fs::path& file, const std::vector<T>& values) {
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(T)));
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
}

nlohmann::json vec(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

void writeScene(const solo::RenderScene& scene, const solo::PathTracerOptions& options, const fs::path& dir) {
  std::vector<float> vertices, reflectance, emission;
  std::vector<std::uint32_t> faces;
  for (const auto& v : scene.vertices) vertices.insert(vertices.end(), {v.x(), v.y(), v.z()});
  for (std::size_t f = 0; f < scene.faces.size(); ++f) {
    faces.insert(faces.end(), scene.faces[f].begin(), scene.faces[f].end());
    const Eigen::Vector3f& r = scene.face_reflectance[f];
    reflectance.insert(reflectance.end(), {r.x(), r.y(), r.z()});
    const int e = scene.face_emitter.empty() ? -1 : scene.face_emitter[f];
    const Eigen::Vector3f l = e >= 0 ? scene.emitters[e].radiance : Eigen::Vector3f::Zero();
    emission.insert(emission.end(), {l.x(), l.y(), l.z()});
  }
  writeArray(dir / "vertices.f32", vertices);
  writeArray(dir / "faces.u32", faces);
  writeArray(dir / "face_reflectance.f32", reflectance);
  writeArray(dir / "face_emission.f32", emission);
  nlohmann::json j;
  j["format"] = "solo-blender-scene/1";
  j["frame"] = "OpenCV camera frame (x right, y down, z forward), metres; camera at the origin";
  j["colour"] = "XYZ relative to E, rendered per channel: give it to Cycles as linear RGB, untouched";
  j["camera"] = {{"fx", scene.camera.fx}, {"fy", scene.camera.fy}, {"cx", scene.camera.cx},
                 {"cy", scene.camera.cy}, {"width", scene.camera.width}, {"height", scene.camera.height}};
  j["mesh"] = {{"vertices", "vertices.f32"}, {"faces", "faces.u32"}, {"face_reflectance", "face_reflectance.f32"},
               {"face_emission", "face_emission.f32"}, {"vertex_count", scene.vertices.size()},
               {"face_count", scene.faces.size()}};
  j["rectangle_lights"] = nlohmann::json::array();
  for (const auto& light : scene.rectangle_lights)
    j["rectangle_lights"].push_back({{"centre", vec(light.centre)}, {"normal", vec(light.normal)},
                                     {"edge_u", vec(light.edge_u)}, {"edge_v", vec(light.edge_v)},
                                     {"radiance", vec(light.radiance)}, {"spread_rad", light.spread_rad}});
  j["emitters"] = scene.emitters.size();
  j["max_bounces"] = options.max_bounces;
  std::ofstream(dir / "scene.json") << j.dump(2) << "\n";
}

// Whether pixel (x, y) counts in the error: not where the reference saw an emitter (`mask`), and
// not on the image's outermost rows and columns. A depth mesh ends at the outermost pixel
// centres; solo's camera samples stay within them (`film_within_pixel_centres`), Cycles samples
// the whole pixel and sees the black world beyond the mesh's edge. On the headlights-only scene
// that border, 0.9 % of the pixels, carried 95 % of Cycles' squared error at 512 samples and held
// it at 0.054 whatever the samples; without it Cycles' error falls as 1 / sqrt(n).
bool counted(const cv::Mat& mask, int x, int y) {
  if (x == 0 || y == 0 || x + 1 == mask.cols || y + 1 == mask.rows) return false;
  return mask.at<float>(y, x) == 0;
}

double relativeRmse(const cv::Mat& image, const cv::Mat& reference, const cv::Mat& mask, double* mean_ratio) {
  double sum = 0, norm = 0, image_sum = 0, reference_sum = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (!counted(mask, x, y)) continue;
      const double r = reference.ptr<float>(y)[x * reference.channels() + 1];
      const double v = image.ptr<float>(y)[x * image.channels() + 1];
      sum += (v - r) * (v - r);
      norm += r * r;
      image_sum += v;
      reference_sum += r;
    }
  if (mean_ratio) *mean_ratio = reference_sum > 0 ? image_sum / reference_sum : 0;
  return norm > 0 ? std::sqrt(sum / norm) : 0;
}

int exportScene(int argc, char** argv, bool reuse_reference) {
  if (argc < 4)
    throw std::runtime_error("usage: export_blender_scene export|runs SCENE OUT_DIR [WxH] [REFERENCE_SPP] [SAMPLERS] [nee]");
  const std::string name = argv[2];
  const fs::path dir = argv[3];
  int width = 480, height = 270, reference_spp = 4096;
  if (argc > 4 && std::sscanf(argv[4], "%dx%d", &width, &height) != 2) throw std::runtime_error("bad size");
  if (argc > 5 && std::string(argv[5]) != "-") reference_spp = std::atoi(argv[5]);
  std::vector<solo::SamplerKind> samplers = {solo::SamplerKind::Sobol, solo::SamplerKind::Independent};
  if (argc > 6) {
    samplers.clear();
    std::stringstream list(argv[6]);
    for (std::string item; std::getline(list, item, ',');) samplers.push_back(solo::parseSamplerKind(item));
  }
  const bool nee_variants = argc > 7 && std::string(argv[7]) == "nee";
  const bool clamp_variants = argc > 7 && std::string(argv[7]) == "clamp";
  const bool roulette_variants = argc > 7 && std::string(argv[7]) == "roulette";
  const bool split_variants = argc > 7 && std::string(argv[7]) == "split";
  const bool adaptive_only = argc > 7 && std::string(argv[7]) == "adaptive";
  solo::RenderScene scene;
  if (name == "night") scene = nightStreet(width, height);
  else if (name == "plane-area") scene = litPlane(width, height, false);
  else if (name == "plane-emitter") scene = litPlane(width, height, true);
  else scene = sceneKind(name, width, height);
  scene.face_shading_normal.clear();
  fs::create_directories(dir);
  solo::PathTracerOptions o;
  o.progress = false;
  o.diffuse = solo::DiffuseModel::Lambert;
  if (!reuse_reference) writeScene(scene, o, dir);  // `runs` keeps the files the reference was made from
  std::printf("%s %dx%d: %zu triangles, %zu emitters, %zu rectangle lights\n", name.c_str(), width, height,
              scene.faces.size(), scene.emitters.size(), scene.rectangle_lights.size());

  cv::Mat reference, mask;
  if (reuse_reference) {
    reference = solo::readImageRaw(dir / "solo_reference.exr");
    mask = solo::readImageRaw(dir / "emitter_mask.exr");
  } else {
    // Two independent halves (seeds 1000 and 1001): the reference is their mean, and its own
    // noise is measured from their difference, (h1 - h2) / 2 being the mean's error in
    // expectation. The tracer's per-pixel standard errors ignore Sobol stratification and miss
    // fireflies, so they do not bound it.
    o.min_samples = o.max_samples = std::max(1, reference_spp / 2);
    solo::Stopwatch reference_clock;
    const double cpu_start = processCpuSeconds();
    o.seed = 1000;
    const solo::RenderOutput first = solo::renderPathTraced(scene, o);
    o.seed = 1001;
    const solo::RenderOutput second = solo::renderPathTraced(scene, o);
    std::printf("reference: 2 x %d spp, seeds 1000 and 1001, %.1f s, %.1f cpu s\n", o.max_samples,
                reference_clock.seconds(), processCpuSeconds() - cpu_start);
    reference = 0.5 * (first.radiance + second.radiance);
    // Every pixel where some sample of the reference's camera rays hit an emitter, also a
    // far lamp covering a sliver of the pixel: there the pixel's value is the emitter's
    // radiance times its coverage, a sampling of the pixel's area, not of light transport.
    mask = cv::Mat(first.emitter_coverage.size(), CV_32F);
    mask.setTo(0.f);
    mask.setTo(1.f, first.emitter_coverage > 0.f);
    mask.setTo(1.f, second.emitter_coverage > 0.f);
    std::printf("reference relative noise (two halves): %.4f\n", relativeRmse(first.radiance, reference, mask, nullptr));
    std::fflush(stdout);
    solo::writeImage(dir / "solo_reference.exr", reference);
    solo::writeImage(dir / "emitter_mask.exr", mask);
  }

  std::ofstream csv(dir / (reuse_reference ? "solo_runs_again.csv" : "solo_runs.csv"));
  csv << "settings,spp_mean,seconds,cpu_seconds,relative_rmse,mean_ratio\n";
  std::printf("%-22s %8s %9s %9s %14s %10s\n", "solo settings", "spp", "seconds", "cpu_s", "relative_rmse",
              "mean_ratio");
  const auto run = [&](const std::string& label, solo::PathTracerOptions options) -> double {
    options.seed = std::getenv("SOLO_SEED") ? static_cast<std::uint64_t>(std::atoi(std::getenv("SOLO_SEED"))) : 7;
    applyNearFieldSetting(options);
    solo::Stopwatch clock;
    const double cpu_start = processCpuSeconds();
    const solo::RenderOutput out = solo::renderPathTraced(scene, options);
    const double seconds = clock.seconds(), cpu_seconds = processCpuSeconds() - cpu_start;
    double ratio = 0;
    const double error = relativeRmse(out.radiance, reference, mask, &ratio);
    double spp = cv::mean(out.samples)[0];
    // The ImageError rule's pilot render (a quarter of the resolution) counts toward the samples.
    if (const solo::MetricValue* pilot = out.report.find("pilot_samples_per_pixel")) spp += std::get<double>(*pilot);
    std::printf("%-22s %8.1f %9.3f %9.3f %14.4f %10.4f\n", label.c_str(), spp, seconds, cpu_seconds, error, ratio);
    csv << label << "," << spp << "," << seconds << "," << cpu_seconds << "," << error << "," << ratio << std::endl;
    std::string file = "solo_" + label + ".exr";  // for `compare` (error concentration) and viewing
    std::replace(file.begin(), file.end(), ' ', '_');
    solo::writeImage(dir / file, out.radiance);
    std::fflush(stdout);
    return spp;
  };
  // Both per-sample samplers (sobol is the default); the reference above uses the default.
  for (const solo::SamplerKind kind : samplers) {
    const std::string suffix = std::string(" ") + solo::samplerKindName(kind);
    for (int spp : {1, 4, 16, 64}) {
      if (adaptive_only) break;
      solo::PathTracerOptions fixed = o;
      fixed.min_samples = fixed.max_samples = spp;
      fixed.sampler = kind;
      run("fixed " + std::to_string(spp) + suffix, fixed);
    }
    solo::PathTracerOptions defaults;
    defaults.progress = false;
    defaults.diffuse = solo::DiffuseModel::Lambert;
    defaults.sampler = kind;
    // SOLO_RELATIVE_ERROR and SOLO_ADAPTIVE_RULE=threshold change the default adaptive run's
    // target and rule (AdaptiveRule::PixelThreshold), for the adaptive-against-fixed table.
    if (const char* target = std::getenv("SOLO_RELATIVE_ERROR")) defaults.relative_error = std::atof(target);
    if (const char* rule = std::getenv("SOLO_ADAPTIVE_RULE"); rule && std::string(rule) == "threshold")
      defaults.adaptive_rule = solo::AdaptiveRule::PixelThreshold;
    const double adaptive_spp = run("default adaptive" + suffix, defaults);
    // Fixed sampling at the adaptive run's mean samples per pixel: adaptive sampling pays only
    // if it beats this.
    solo::PathTracerOptions equal = o;
    equal.min_samples = equal.max_samples = std::max(1, static_cast<int>(std::lround(adaptive_spp)));
    equal.sampler = kind;
    run("fixed at adaptive mean" + suffix, equal);
  }
  // A/B runs at 16 and 64 spp with the first sampler: `name` labels a variant that `set` makes.
  using Variant = std::pair<std::string, std::function<void(solo::PathTracerOptions&)>>;
  std::vector<Variant> variants;
  if (roulette_variants)
    for (int after : {1, 2, 4})
      variants.push_back({" roulette after " + std::to_string(after), [after](auto& t) { t.russian_roulette_after = after; }});
  if (clamp_variants)
    for (float clamp : {30.f, 100.f, 300.f, 1000.f, 3000.f})
      variants.push_back({" clamp " + std::to_string(static_cast<int>(clamp)), [clamp](auto& t) { t.indirect_clamp = clamp; }});
  if (split_variants)
    for (int splits : {4, 8})
      for (float distance : {0.5f, 2.f})
        variants.push_back({" split " + std::to_string(splits) + " within " + std::to_string(distance).substr(0, 3) + "m",
                            [splits, distance](auto& t) {
                              t.emission_splits = splits;
                              t.split_distance_m = distance;
                            }});
  if (nee_variants) {
    variants.push_back({" area-emitters", [](auto& t) { t.solid_angle_emitter_sampling = false; }});
    variants.push_back({" ray-per-light", [](auto& t) { t.one_shadow_ray = false; }});
    variants.push_back({" area+ray-per-light", [](auto& t) {
                          t.solid_angle_emitter_sampling = false;
                          t.one_shadow_ray = false;
                        }});
  }
  const std::string suffix = std::string(" ") + solo::samplerKindName(samplers.front());
  for (int spp : {16, 64})
    for (const auto& [name, set] : variants) {
      solo::PathTracerOptions fixed = o;
      fixed.min_samples = fixed.max_samples = spp;
      fixed.sampler = samplers.front();
      set(fixed);
      run("fixed " + std::to_string(spp) + suffix + name, fixed);
    }
  return 0;
}

int compare(int argc, char** argv) {
  if (argc < 4) throw std::runtime_error("usage: export_blender_scene compare OUT_DIR IMAGE.exr");
  const fs::path dir = argv[2];
  const cv::Mat reference = solo::readImageRaw(dir / "solo_reference.exr");
  const cv::Mat mask = solo::readImageRaw(dir / "emitter_mask.exr");
  const cv::Mat image = solo::readImageRaw(argv[3]);
  if (image.rows != reference.rows || image.cols != reference.cols || image.channels() < 3)
    throw std::runtime_error(std::string(argv[3]) + ": not the reference's size or fewer than 3 channels");
  double ratio = 0;
  const double error = relativeRmse(image, reference, mask, &ratio);
  // How concentrated the error is: the share of the squared error in the worst 1 % of the pixels
  // (near 1 % for even noise, near 1 for a few fireflies).
  struct PixelError {
    double square;
    int x, y;
  };
  const auto luminance = [](const cv::Mat& m, int x, int y) { return m.ptr<float>(y)[x * m.channels() + 1]; };
  std::vector<PixelError> squares;
  double total = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (!counted(mask, x, y)) continue;
      const double d = luminance(image, x, y) - luminance(reference, x, y);
      squares.push_back({d * d, x, y});
      total += d * d;
    }
  std::sort(squares.begin(), squares.end(),
            [](const PixelError& a, const PixelError& b) { return a.square > b.square; });
  double worst = 0;
  for (std::size_t i = 0; i < squares.size() / 100; ++i) worst += squares[i].square;
  std::printf("relative_rmse %.5f mean_ratio %.5f worst_1%%_share %.3f\n", error, ratio,
              total > 0 ? worst / total : 0.0);
  for (std::size_t i = 0; i < std::min<std::size_t>(squares.size(), 3); ++i) {
    const PixelError& p = squares[i];
    std::printf("  worst pixel (%d, %d): image Y %.4g reference Y %.4g\n", p.x, p.y, luminance(image, p.x, p.y),
                luminance(reference, p.x, p.y));
  }
  // The same without the pixels next to a directly seen emitter (the mask grown by 1 and 2
  // pixels): a pixel whose footprint covers part of a lamp that its first sample missed counts
  // as non-emitting, yet its samples that hit the lamp carry the lamp's radiance.
  for (const int grow : {1, 2}) {
    cv::Mat grown;
    cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * grow + 1, 2 * grow + 1)));
    double ratio_grown = 0;
    std::size_t left = 0;
    for (int y = 0; y < grown.rows; ++y)
      for (int x = 0; x < grown.cols; ++x) left += counted(grown, x, y);
    std::printf("without pixels within %d of a seen emitter (%zu pixels left): relative_rmse %.5f\n", grow, left,
                relativeRmse(image, reference, grown, &ratio_grown));
  }
  return 0;
}

// A render split into its light components (PathTracerOptions::component).
struct ComponentImages {
  cv::Mat direct, indirect;  // CV_32FC3
  cv::Mat all() const { return direct + indirect; }
};

// An image's squared errors of Y against the reference on the pixels a mask leaves, by source;
// sums, so that several seeds' images pool.
struct ErrorSums {
  double total = 0;                  // the image's (direct + indirect) squared error
  double direct = 0, indirect = 0;   // each component's own; the rest of total is their cross term
  double worst = 0;                  // the worst 0.1 % of the pixels' (fireflies)
  double worst_direct = 0, worst_indirect = 0;  // the components' own squared errors on those pixels
  double worst_above = 0;  // the part of worst on pixels where the image is above the reference
  double beside_emitter = 0;  // the part of total on pixels within 1 pixel of a seen emitter
  double norm = 0;                   // the reference's squared Y
  double direct_light = 0, indirect_light = 0;  // the reference's summed Y of each component

  ErrorSums& operator+=(const ErrorSums& o) {
    total += o.total, direct += o.direct, indirect += o.indirect, worst += o.worst;
    worst_direct += o.worst_direct, worst_indirect += o.worst_indirect, worst_above += o.worst_above, norm += o.norm;
    beside_emitter += o.beside_emitter;
    direct_light += o.direct_light, indirect_light += o.indirect_light;
    return *this;
  }
  double relativeRmse() const { return norm > 0 ? std::sqrt(total / norm) : 0; }
  double share(double part) const { return total > 0 ? part / total : 0; }
  double fireflyIndirect() const {
    return worst_direct + worst_indirect > 0 ? worst_indirect / (worst_direct + worst_indirect) : 0;
  }
  double indirectLight() const {
    return direct_light + indirect_light > 0 ? indirect_light / (direct_light + indirect_light) : 0;
  }
};

// Error sums of `image` against `reference` on the pixels where `mask` is 0.
ErrorSums errorSums(const ComponentImages& image, const ComponentImages& reference, const cv::Mat& mask) {
  const auto luminance = [](const cv::Mat& m, int x, int y) {
    return static_cast<double>(m.ptr<float>(y)[x * m.channels() + 1]);
  };
  std::vector<double> squares, direct_squares, indirect_squares;
  std::vector<bool> above;
  cv::Mat grown;  // the mask grown by a pixel: its new pixels are beside a seen emitter
  cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  ErrorSums e;
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      if (mask.at<float>(y, x) != 0) continue;
      const double direct_reference = luminance(reference.direct, x, y);
      const double indirect_reference = luminance(reference.indirect, x, y);
      const double direct_error = luminance(image.direct, x, y) - direct_reference;
      const double indirect_error = luminance(image.indirect, x, y) - indirect_reference;
      squares.push_back((direct_error + indirect_error) * (direct_error + indirect_error));
      direct_squares.push_back(direct_error * direct_error);
      indirect_squares.push_back(indirect_error * indirect_error);
      above.push_back(direct_error + indirect_error > 0);
      if (grown.at<float>(y, x) != 0) e.beside_emitter += squares.back();
      e.norm += (direct_reference + indirect_reference) * (direct_reference + indirect_reference);
      e.direct_light += direct_reference;
      e.indirect_light += indirect_reference;
    }
  const auto sum = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); };
  e.total = sum(squares);
  e.direct = sum(direct_squares);
  e.indirect = sum(indirect_squares);
  if (squares.empty()) return e;
  std::vector<std::size_t> order(squares.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const std::size_t worst = std::max<std::size_t>(1, squares.size() / 1000);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(worst), order.end(),
                    [&](std::size_t a, std::size_t b) { return squares[a] > squares[b]; });
  for (std::size_t k = 0; k < worst; ++k) {
    e.worst += squares[order[k]];
    e.worst_direct += direct_squares[order[k]];
    e.worst_indirect += indirect_squares[order[k]];
    if (above[order[k]]) e.worst_above += squares[order[k]];
  }
  return e;
}

// The scene rendered once per component with `options`; `cpu_seconds` receives the CPU time.
ComponentImages renderComponents(const solo::PreparedRenderScene& prepared, solo::PathTracerOptions options,
                                 double* cpu_seconds, cv::Mat* emitter_coverage = nullptr) {
  const double cpu_start = processCpuSeconds();
  ComponentImages images;
  options.component = solo::PathComponent::Direct;
  const solo::RenderOutput direct = solo::renderPathTraced(prepared, prepared.scene().camera, options);
  images.direct = direct.radiance;
  options.component = solo::PathComponent::Indirect;
  images.indirect = solo::renderPathTraced(prepared, prepared.scene().camera, options).radiance;
  if (emitter_coverage) *emitter_coverage = direct.emitter_coverage;
  *cpu_seconds = processCpuSeconds() - cpu_start;
  return images;
}

// The reference of each component in `dir` (error_reference_direct.exr, _indirect.exr and
// error_emitter_mask.exr), rendered at `spp` Sobol samples with seed 1000 unless already there.
ComponentImages componentReference(const solo::PreparedRenderScene& prepared, const solo::PathTracerOptions& base,
                                   int spp, const fs::path& dir, cv::Mat* mask) {
  const fs::path direct_file = dir / "error_reference_direct.exr", indirect_file = dir / "error_reference_indirect.exr";
  const fs::path mask_file = dir / "error_emitter_mask.exr";
  if (fs::exists(direct_file) && fs::exists(indirect_file) && fs::exists(mask_file)) {
    *mask = solo::readImageRaw(mask_file);
    std::printf("reference: the one in %s\n", dir.c_str());
    return {solo::readImageRaw(direct_file), solo::readImageRaw(indirect_file)};
  }
  solo::PathTracerOptions o = base;
  o.min_samples = o.max_samples = spp;
  o.seed = 1000;
  double cpu_seconds = 0;
  cv::Mat coverage;
  const ComponentImages reference = renderComponents(prepared, o, &cpu_seconds, &coverage);
  std::printf("reference: %d spp per component, seed 1000, %.1f cpu s\n", spp, cpu_seconds);
  *mask = cv::Mat::zeros(coverage.size(), CV_32F);
  mask->setTo(1.f, coverage > 0.f);
  fs::create_directories(dir);
  solo::writeImage(direct_file, reference.direct);
  solo::writeImage(indirect_file, reference.indirect);
  solo::writeImage(mask_file, *mask);
  return reference;
}

// The seeds of the error-sources runs: SOLO_SEED (7 unless set) and the `count` - 1 after it.
std::vector<std::uint64_t> runSeeds(int count) {
  const char* seed = std::getenv("SOLO_SEED");
  const std::uint64_t first = seed ? static_cast<std::uint64_t>(std::atoi(seed)) : 7;
  std::vector<std::uint64_t> seeds;
  for (int k = 0; k < std::max(1, count); ++k) seeds.push_back(first + static_cast<std::uint64_t>(k));
  return seeds;
}

int errorSourcesCommand(int argc, char** argv) {
  if (argc < 4)
    throw std::runtime_error(
        "usage: export_blender_scene error-sources SCENE OUT_DIR [WxH] [REFERENCE_SPP] [SPP] [SEEDS] [ADAPTIVE_SEEDS]");
  const std::string name = argv[2];
  const fs::path dir = argv[3];
  int width = 240, height = 135;
  if (argc > 4 && std::sscanf(argv[4], "%dx%d", &width, &height) != 2) throw std::runtime_error("bad size");
  const int reference_spp = argc > 5 ? std::atoi(argv[5]) : 1024, spp = argc > 6 ? std::atoi(argv[6]) : 16;
  const int seed_count = argc > 7 ? std::atoi(argv[7]) : 8, adaptive_seed_count = argc > 8 ? std::atoi(argv[8]) : 2;
  const solo::RenderScene scene = name == "night" ? nightStreet(width, height) : sceneKind(name, width, height);
  const solo::PreparedRenderScene prepared(scene);
  solo::PathTracerOptions base;
  base.progress = false;
  base.diffuse = solo::DiffuseModel::Lambert;
  applyNearFieldSetting(base);
  cv::Mat mask;
  const ComponentImages reference = componentReference(prepared, base, reference_spp, dir, &mask);

  // Fixed sampling, each component from the same paths: the error's split by source.
  solo::PathTracerOptions fixed = base;
  fixed.min_samples = fixed.max_samples = spp;
  ErrorSums e;
  double fixed_cpu = 0;
  for (const std::uint64_t seed : runSeeds(seed_count)) {
    fixed.seed = seed;
    double cpu_seconds = 0;
    const ComponentImages run = renderComponents(prepared, fixed, &cpu_seconds);
    e += errorSums(run, reference, mask);
    fixed_cpu += cpu_seconds;
    if (seed == runSeeds(1).front()) {  // the first run, to locate where its error sits
      solo::writeImage(dir / "error_fixed_direct.exr", run.direct);
      solo::writeImage(dir / "error_fixed_indirect.exr", run.indirect);
    }
  }
  std::printf("fixed %d spp, %d seeds (%.1f cpu s): relative_rmse %.4f; squared error: direct %.3f indirect %.3f "
              "cross %.3f; worst 0.1 %% of pixels %.3f (indirect %.3f of theirs, %.3f above the reference); indirect "
              "light %.3f; pixels beside a seen emitter %.3f\n",
              spp, seed_count, fixed_cpu, e.relativeRmse(), e.share(e.direct), e.share(e.indirect),
              e.share(e.total - e.direct - e.indirect), e.share(e.worst), e.fireflyIndirect(),
              e.worst > 0 ? e.worst_above / e.worst : 0, e.indirectLight(), e.share(e.beside_emitter));

  // The default adaptive settings render the whole light only: their error and firefly share.
  solo::PathTracerOptions adaptive = base;
  ErrorSums a;
  double adaptive_spp = 0;
  const double cpu_start = processCpuSeconds();
  const std::vector<std::uint64_t> adaptive_seeds = runSeeds(adaptive_seed_count);
  for (const std::uint64_t seed : adaptive_seeds) {
    adaptive.seed = seed;
    const solo::RenderOutput out = solo::renderPathTraced(prepared, scene.camera, adaptive);
    adaptive_spp += cv::mean(out.samples)[0] / static_cast<double>(adaptive_seeds.size());
    if (const solo::MetricValue* pilot = out.report.find("pilot_samples_per_pixel"))
      adaptive_spp += std::get<double>(*pilot) / static_cast<double>(adaptive_seeds.size());
    const cv::Mat zeros = cv::Mat::zeros(out.radiance.size(), out.radiance.type());
    a += errorSums({out.radiance, zeros}, {reference.all(), zeros}, mask);
  }
  std::printf("default adaptive, %zu seeds (%.0f spp, %.1f cpu s): relative_rmse %.4f; worst 0.1 %% of pixels %.3f\n",
              adaptive_seeds.size(), adaptive_spp, processCpuSeconds() - cpu_start, a.relativeRmse(), a.share(a.worst));
  const auto percent = [](double share) { return static_cast<int>(std::lround(100 * share)); };
  std::printf("row: %d %% | %.3f | %d %% | %d %% | %d %% | %d %% (%d %% indirect) | %.0f spp: %.3f, %d %%\n",
              percent(e.indirectLight()), e.relativeRmse(), percent(e.share(e.direct)), percent(e.share(e.indirect)),
              percent(e.share(e.total - e.direct - e.indirect)), percent(e.share(e.worst)),
              percent(e.fireflyIndirect()), adaptive_spp, a.relativeRmse(), percent(a.share(a.worst)));
  return 0;
}

}  // namespace

// Where a pixel's error comes from: N estimates of SPP samples (default 2, independent) of one pixel (a 1x1
// camera over it, seeds 1..N), their mean and spread, the largest ones, and the rays of the
// largest (origins, directions, lengths) to locate the path that made it.
int probe(int argc, char** argv) {
  if (argc < 7) throw std::runtime_error("usage: export_blender_scene probe SCENE WxH X Y N [SPP] [SAMPLER]");
  int width = 0, height = 0;
  if (std::sscanf(argv[3], "%dx%d", &width, &height) != 2) throw std::runtime_error("bad size");
  const int x = std::atoi(argv[4]), y = std::atoi(argv[5]), n = std::atoi(argv[6]);
  const std::string name = argv[2];
  solo::RenderScene scene;
  if (name == "night") scene = nightStreet(width, height);
  else scene = sceneKind(name, width, height);
  scene.face_shading_normal.clear();
  const solo::PreparedRenderScene prepared(scene);
  solo::PinholeCamera pixel = scene.camera;
  pixel.cx -= x;
  pixel.cy -= y;
  pixel.width = pixel.height = 1;
  solo::PathTracerOptions o;
  o.progress = false;
  o.diffuse = solo::DiffuseModel::Lambert;
  // The whole pixel, as the full image samples an inner pixel: a one-pixel film's outermost
  // pixel centre is its only one, and every camera ray would go through it.
  o.film_within_pixel_centres = false;
  applyNearFieldSetting(o);
  o.sampler = argc > 8 ? solo::parseSamplerKind(argv[8]) : solo::SamplerKind::Independent;
  o.min_samples = o.max_samples = argc > 7 ? std::max(2, std::atoi(argv[7])) : 2;
  std::vector<std::pair<double, int>> values;
  double sum = 0, sum2 = 0;
  for (int seed = 1; seed <= n; ++seed) {
    o.seed = static_cast<std::uint64_t>(seed);
    const double v = solo::renderPathTraced(prepared, pixel, o).radiance.at<cv::Vec3f>(0, 0)[1];
    values.emplace_back(v, seed);
    sum += v;
    sum2 += v * v;
  }
  std::sort(values.rbegin(), values.rend());
  const double mean = sum / n;
  std::printf("pixel (%d, %d): %d estimates of %d samples (%s), mean %.4g, standard deviation %.4g\n", x, y, n,
              o.max_samples, solo::samplerKindName(o.sampler), mean,
              std::sqrt(std::max(0.0, sum2 / n - mean * mean)));
  double top = 0;
  for (int k = 0; k < std::min(n, 10); ++k) {
    top += values[static_cast<std::size_t>(k)].first;
    std::printf("  seed %d: %.4g (top %d carry %.1f %% of the sum)\n", values[static_cast<std::size_t>(k)].second,
                values[static_cast<std::size_t>(k)].first, k + 1, 100 * top / sum);
  }
  std::vector<solo::RecordedRay> rays;
  o.seed = static_cast<std::uint64_t>(values.front().second);
  o.ray_log = &rays;
  solo::renderPathTraced(prepared, pixel, o);
  std::printf("rays of seed %d (origin, direction, t_far for shadow rays):\n", values.front().second);
  for (const solo::RecordedRay& r : rays)
    std::printf("  %s o (%.3f %.3f %.3f) d (%.3f %.3f %.3f) %.3f\n", r.shadow ? "shadow " : "closest", r.origin.x(),
                r.origin.y(), r.origin.z(), r.direction.x(), r.direction.y(), r.direction.z(), r.t_far);
  return 0;
}

int main(int argc, char** argv) {
  try {
    if (argc > 1 && std::string(argv[1]) == "export") return exportScene(argc, argv, false);
    if (argc > 1 && std::string(argv[1]) == "runs") return exportScene(argc, argv, true);
    if (argc > 1 && std::string(argv[1]) == "compare") return compare(argc, argv);
    if (argc > 1 && std::string(argv[1]) == "probe") return probe(argc, argv);
    if (argc > 1 && std::string(argv[1]) == "error-sources") return errorSourcesCommand(argc, argv);
    std::fprintf(stderr, "usage: export_blender_scene export|compare ...\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "export_blender_scene: %s\n", e.what());
    return 2;
  }
}
