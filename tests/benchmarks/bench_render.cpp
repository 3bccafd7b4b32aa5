// Renderer measurements on a synthetic night street (solo synth's box scene with its lights
// switched on): raw Embree ray throughput against the tracer's, and error at equal time of the
// three light samplers against a converged reference.
// Run: build/release/tests/benchmarks/bench_render [WIDTHxHEIGHT] [reference_spp] [csv]
//  or: build/release/tests/benchmarks/bench_render efficiency MANIFEST [WIDTHxHEIGHT]
//      the efficiency line alone on the scene `solo night` renders from a scene manifest with
//      its default preset (the mesh at the image resolution; the camera scaled to WIDTHxHEIGHT,
//      480x270 unless given, so that one-thread renders take seconds).
//  or: build/release/tests/benchmarks/bench_render trace MANIFEST [WIDTHxHEIGHT] [REPEATS]
//      that line's tracer run alone, for a profiler (perf record -g ...).

#include "night_street.h"
#include "pipeline_scene.h"

#include <solo/core/report.h>
#include <solo/lighting/light_category.h>
#include <solo/render/path_tracer.h>
#include <solo/render/ray_caster.h>
#include <solo/synth/street_scene.h>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <map>
#include <random>

namespace {

solo::RenderScene nightStreet(int width, int height) {
  return solo::bench::nightStreet({width, height});
}

// CPU time of the process, seconds: unlike the wall clock, it leaves out the time the host
// gives this machine's core to others (the one-thread measurements run on one thread).
double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Raw Embree, one pass over image row y: its camera rays, then one random bounce per hit,
// single rays as the tracer casts them, on the calling thread. Closest-hit rays only (the
// tracer's shadow rays are cheaper), through intersectSlot: Embree's rtcIntersect1 and nothing
// after it. Returns the rays cast.
std::int64_t rawEmbreeRow(const solo::RenderScene& scene, const solo::RayCaster& caster, int y, std::mt19937& rng) {
  std::normal_distribution<float> g(0, 1);
  std::int64_t rays = 0;
  for (int x = 0; x < scene.camera.width; ++x) {
    const Eigen::Vector3f d = Eigen::Vector3f(static_cast<float>((x - scene.camera.cx) / scene.camera.fx),
                                              static_cast<float>((y - scene.camera.cy) / scene.camera.fy), 1.f)
                                  .normalized();
    const solo::SlotHit hit = caster.intersectSlot(Eigen::Vector3f::Zero(), d);
    ++rays;
    if (!hit.hit) continue;
    const Eigen::Vector3f p = d * hit.distance * 0.999f;
    caster.intersectSlot(p, Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized());
    ++rays;
  }
  return rays;
}

// Four passes over the image, row by row, on the calling thread.
struct RawRun {
  std::int64_t rays = 0;
  double wall_seconds = 0, cpu_seconds = 0;  // the process's CPU time
};
RawRun rawEmbreeRun(const solo::RenderScene& scene, const solo::RayCaster& caster) {
  std::mt19937 rng(1);
  solo::Stopwatch clock;
  const double cpu_start = cpuSeconds();
  RawRun run;
  for (int pass = 0; pass < 4; ++pass)
    for (int y = 0; y < scene.camera.height; ++y) run.rays += rawEmbreeRow(scene, caster, y, rng);
  run.wall_seconds = clock.seconds();
  run.cpu_seconds = cpuSeconds() - cpu_start;
  return run;
}
double rawEmbreeRaysPerSecond(const solo::RenderScene& scene, const solo::RayCaster& caster) {
  const RawRun run = rawEmbreeRun(scene, caster);
  return static_cast<double>(run.rays) / run.wall_seconds;
}

// The same four passes on every thread the machine has: each pass's rows in parallel, each
// row's bounces from its own seeded generator. The passes stay the outer loop, as on one
// thread: a row traced four times in a row finds its camera rays' nodes in the cache and ran
// 1.2x faster, which the tracer never gets.
double rawEmbreeRaysPerSecondAllThreads(const solo::RenderScene& scene, const solo::RayCaster& caster) {
  std::atomic<std::int64_t> rays{0};
  solo::Stopwatch clock;
  for (int pass = 0; pass < 4; ++pass)
    tbb::parallel_for(0, scene.camera.height, [&](int y) {
      std::mt19937 rng(static_cast<std::uint32_t>(pass * scene.camera.height + y) + 1);
      rays += rawEmbreeRow(scene, caster, y, rng);
    });
  return static_cast<double>(rays.load()) / clock.seconds();
}

// The tracer's own rays (recorded by PathTracerOptions::ray_log) cast again by a bare loop on
// the calling thread: what Embree alone takes for exactly the tracer's workload.
// With `triangle_lookup`, closest hits go through RayCaster::intersect instead, which also finds
// the input triangle and its barycentrics (a cache miss per hit on a large mesh): the baseline
// of the measurements before the tracer read its face data by slot.
double replayRaysPerSecond(const solo::RayCaster& caster, const std::vector<solo::RecordedRay>& rays,
                           bool triangle_lookup = false) {
  solo::Stopwatch clock;
  std::int64_t hits = 0;
  for (const solo::RecordedRay& r : rays)
    hits += r.shadow           ? caster.occluded(r.origin, r.direction, 0.f, r.t_far)
            : triangle_lookup ? caster.intersect(r.origin, r.direction).hit
                              : caster.intersectSlot(r.origin, r.direction).hit;
  const double seconds = clock.seconds();
  if (hits < 0) std::printf("unreachable\n");  // keeps the loop's results alive
  return static_cast<double>(rays.size()) / seconds;
}

// Relative RMSE of Y over the pixels where no reference sample saw an emitter (a lamp that
// covers a sliver of a pixel would otherwise carry most of the error).
double relativeRmse(const cv::Mat& image, const cv::Mat& reference, const cv::Mat& emitter_coverage) {
  double sum = 0, norm = 0;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      if (emitter_coverage.at<float>(y, x) > 0.f) continue;
      const double r = reference.at<cv::Vec3f>(y, x)[1], v = image.at<cv::Vec3f>(y, x)[1];
      sum += (v - r) * (v - r);
      norm += r * r;
    }
  return norm > 0 ? std::sqrt(sum / norm) : 0;
}

// The efficiency line's tracer: 4 spp everywhere, seed 11, no progress bar.
solo::PathTracerOptions efficiencyOptions(solo::LightSamplerKind kind) {
  solo::PathTracerOptions t;
  t.progress = false;
  t.min_samples = t.max_samples = 4;
  t.seed = 11;
  t.light_sampler = kind;
  return t;
}

// Efficiency: raw Embree against the tracer's rays per second on one thread each (so "per
// thread" means the same thing for both, whatever the cores are), alternated five times so
// that machine load hits all alike; medians, with the load average before and after. Then
// nine back-to-back pairs by CPU time (the steadier figure), and both on every thread.
void measureEfficiency(const solo::RenderScene& scene) {
  std::vector<float> vertices;
  for (const auto& v : scene.vertices) vertices.insert(vertices.end(), {v.x(), v.y(), v.z()});
  std::vector<std::uint32_t> indices;
  for (const auto& f : scene.faces) indices.insert(indices.end(), f.begin(), f.end());
  const solo::RayCaster caster(std::move(vertices), std::move(indices));
  // One BVH and light list for every tracer run, so that samples per second are the render's
  // alone (the BVH of a 1080p mesh takes seconds to build).
  const solo::PreparedRenderScene prepared(scene);
  // The default tracer's rays (power sampler, one shadow ray per vertex), recorded once: the
  // same seed casts the same rays in every repeat.
  std::vector<solo::RecordedRay> recorded;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    solo::PathTracerOptions t = efficiencyOptions(solo::LightSamplerKind::Power);
    t.ray_log = &recorded;
    solo::renderPathTraced(prepared, scene.camera, t);
  }
  std::int64_t shadow_rays = 0;
  for (const solo::RecordedRay& r : recorded) shadow_rays += r.shadow;
  double load_before[3] = {0, 0, 0}, load_after[3] = {0, 0, 0};
  getloadavg(load_before, 3);
  std::vector<double> raw, replay, replay_lookup, power, hierarchy, power_samples, hierarchy_samples, per_light, per_light_samples;
  std::vector<double> raw_all, power_all;
  for (int repeat = 0; repeat < 5; ++repeat) {
    raw_all.push_back(rawEmbreeRaysPerSecondAllThreads(scene, caster));
    power_all.push_back(std::get<double>(*solo::renderPathTraced(prepared, scene.camera,
                                                                 efficiencyOptions(solo::LightSamplerKind::Power))
                                              .report.find("rays_per_second")));
    raw.push_back(rawEmbreeRaysPerSecond(scene, caster));
    replay.push_back(replayRaysPerSecond(caster, recorded));
    replay_lookup.push_back(replayRaysPerSecond(caster, recorded, true));
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    for (auto kind : {solo::LightSamplerKind::Power, solo::LightSamplerKind::Hierarchy}) {
      const solo::RenderOutput out = solo::renderPathTraced(prepared, scene.camera, efficiencyOptions(kind));
      const double rate = std::get<double>(*out.report.find("rays_per_second"));
      const double samples = 4.0 * scene.camera.width * scene.camera.height / out.report.seconds;
      (kind == solo::LightSamplerKind::Power ? power : hierarchy).push_back(rate);
      (kind == solo::LightSamplerKind::Power ? power_samples : hierarchy_samples).push_back(samples);
    }
    // The power sampler with a shadow ray per light (the tracer before one_shadow_ray): more,
    // cheaper rays per sample, so more rays per second for fewer samples per second.
    solo::PathTracerOptions t = efficiencyOptions(solo::LightSamplerKind::Power);
    t.one_shadow_ray = false;
    const solo::RenderOutput out = solo::renderPathTraced(prepared, scene.camera, t);
    per_light.push_back(std::get<double>(*out.report.find("rays_per_second")));
    per_light_samples.push_back(4.0 * scene.camera.width * scene.camera.height / out.report.seconds);
  }
  // Paired: raw Embree and the tracer back to back on one thread, by the process's CPU time
  // (which also counts any work or spinning of another thread against the run), in ABBA order
  // (each pair's second run first in the next pair), so that drift in the host's speed hits both
  // alike; the ratio per pair, then its median. The medians above compare runs up to a minute
  // apart, between which this host's speed moves by 10 %.
  std::vector<double> paired;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    for (int pair = 0; pair < 9; ++pair) {
      RawRun raw_run;
      double tracer_cpu_seconds = 0;
      std::int64_t tracer_rays = 0;
      const auto trace = [&] {
        const double start = cpuSeconds();
        const solo::RenderOutput out =
            solo::renderPathTraced(prepared, scene.camera, efficiencyOptions(solo::LightSamplerKind::Power));
        tracer_cpu_seconds = cpuSeconds() - start;
        tracer_rays = std::get<std::int64_t>(*out.report.find("rays"));
      };
      if (pair % 2 == 0) {
        raw_run = rawEmbreeRun(scene, caster);
        trace();
      } else {
        trace();
        raw_run = rawEmbreeRun(scene, caster);
      }
      paired.push_back((static_cast<double>(tracer_rays) / tracer_cpu_seconds) /
                       (static_cast<double>(raw_run.rays) / raw_run.cpu_seconds));
    }
  }
  getloadavg(load_after, 3);
  const double raw_median = median(raw);
  std::printf("efficiency, 1 thread, 4 spp, median of 5 (load average %.1f before, %.1f after): raw Embree %.3f Mrays/s; "
              "tracer power %.3f Mrays/s (%.1f %% of raw, %.3f M samples/s), hierarchy %.3f Mrays/s (%.1f %%, %.3f M "
              "samples/s), power with a shadow ray per light %.3f Mrays/s (%.1f %%, %.3f M samples/s)\n",
              load_before[0], load_after[0], raw_median / 1e6, median(power) / 1e6, 100 * median(power) / raw_median,
              median(power_samples) / 1e6, median(hierarchy) / 1e6, 100 * median(hierarchy) / raw_median,
              median(hierarchy_samples) / 1e6, median(per_light) / 1e6, 100 * median(per_light) / raw_median,
              median(per_light_samples) / 1e6);
  std::printf("efficiency, 1 thread, paired by process CPU time, 9 pairs in ABBA order: tracer (power) / raw Embree "
              "rays per CPU second, median %.1f %% (range %.1f-%.1f %%)\n",
              100 * median(paired), 100 * *std::min_element(paired.begin(), paired.end()),
              100 * *std::max_element(paired.begin(), paired.end()));
  std::printf("efficiency on all %d threads, median of 5: raw Embree %.3f Mrays/s; tracer power %.3f Mrays/s (%.1f %% "
              "of raw)\n",
              tbb::this_task_arena::max_concurrency(), median(raw_all) / 1e6, median(power_all) / 1e6,
              100 * median(power_all) / median(raw_all));
  std::printf("efficiency against the same rays, 1 thread, median of 5: the tracer's (power) %zu rays (%.0f %% shadow "
              "rays) replayed through bare Embree calls %.3f Mrays/s; the tracer %.3f Mrays/s, %.1f %% of it\n",
              recorded.size(), 100.0 * static_cast<double>(shadow_rays) / static_cast<double>(recorded.size()),
              median(replay) / 1e6, median(power) / 1e6, 100 * median(power) / median(replay));
  std::printf("the same rays with the triangle lookup after each closest hit (RayCaster::intersect, the baseline "
              "before slot records): %.3f Mrays/s; the tracer %.1f %% of it\n",
              median(replay_lookup) / 1e6, 100 * median(power) / median(replay_lookup));
}

// The efficiency line's tracer run alone (power sampler, 1 thread, 4 spp), `repeats` times: a
// workload for profilers, whose samples then all come from the tracer.
void traceOnly(const solo::RenderScene& scene, int repeats) {
  const solo::PreparedRenderScene prepared(scene);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<double> rate, cpu_rate;
  for (int repeat = 0; repeat < repeats; ++repeat) {
    const double cpu_start = cpuSeconds();
    const solo::RenderOutput out =
        solo::renderPathTraced(prepared, scene.camera, efficiencyOptions(solo::LightSamplerKind::Power));
    const double cpu = cpuSeconds() - cpu_start;
    rate.push_back(std::get<double>(*out.report.find("rays_per_second")));
    cpu_rate.push_back(static_cast<double>(std::get<std::int64_t>(*out.report.find("rays"))) / cpu);
  }
  std::printf("tracer alone, power sampler, 1 thread, 4 spp, median of %d: %.3f Mrays/s, %.3f Mrays per CPU second\n",
              repeats, median(rate) / 1e6, median(cpu_rate) / 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // lines appear as they are measured
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "efficiency" || mode == "trace") {
    if (argc < 3) {
      std::fprintf(stderr, "usage: bench_render %s MANIFEST [WIDTHxHEIGHT]%s\n", mode.c_str(),
                   mode == "trace" ? " [REPEATS]" : "");
      return 2;
    }
    int width = 480, height = 270;
    if (argc > 3) std::sscanf(argv[3], "%dx%d", &width, &height);
    try {
      const solo::RenderScene scene = solo::bench::pipelineScene(argv[2], width, height);
      if (mode == "efficiency") measureEfficiency(scene);
      else traceOnly(scene, argc > 4 ? std::max(1, std::atoi(argv[4])) : 5);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_render %s: %s\n", mode.c_str(), e.what());
      return 1;
    }
    return 0;
  }
  int width = 480, height = 270, reference_spp = 1024;
  if (argc > 1) std::sscanf(argv[1], "%dx%d", &width, &height);
  if (argc > 2) reference_spp = std::atoi(argv[2]);
  const solo::RenderScene scene = nightStreet(width, height);
  std::printf("night street %dx%d: %zu triangles, %zu lights, 2 headlights\n", width, height, scene.faces.size(),
              scene.emitters.size());

  measureEfficiency(scene);

  solo::PathTracerOptions o;
  o.progress = false;
  o.min_samples = o.max_samples = reference_spp;
  o.seed = 1000;
  solo::Stopwatch reference_clock;
  const solo::RenderOutput reference = solo::renderPathTraced(scene, o);
  std::printf("reference: %d spp, hierarchy sampler, %.1f s, %.2f Mrays/s on all threads\n", reference_spp,
              reference_clock.seconds(), std::get<double>(*reference.report.find("rays_per_second")) / 1e6);

  // What the per-sample sampler costs: 16-spp renders with scrambled Sobol points and with
  // independent PCG32 numbers, alternated five times so machine load hits both alike; medians.
  {
    std::vector<double> rate[2], error[2];
    const solo::SamplerKind kinds[2] = {solo::SamplerKind::Sobol, solo::SamplerKind::Independent};
    for (int repeat = 0; repeat < 5; ++repeat)
      for (int k = 0; k < 2; ++k) {
        solo::PathTracerOptions s = o;
        s.min_samples = s.max_samples = 16;
        s.seed = 7;
        s.sampler = kinds[k];
        const solo::RenderOutput out = solo::renderPathTraced(scene, s);
        rate[k].push_back(std::get<double>(*out.report.find("rays_per_second")) / 1e6);
        error[k].push_back(relativeRmse(out.radiance, reference.radiance, reference.emitter_coverage));
      }
    std::printf("sampler cost, 16 spp, median of 5: sobol %.3f Mrays/s (relative RMSE %.4f), independent %.3f Mrays/s "
                "(%.4f): sobol/independent rays/s %.3f\n",
                median(rate[0]), error[0][0], median(rate[1]), error[1][0], median(rate[0]) / median(rate[1]));
  }

  // Next-event estimation (docs/rendering.md, Integrator): the default (one shadow ray per
  // vertex, solid-angle sampling of close emitters) against a shadow ray per light and against
  // emitters sampled by area, 16-spp renders alternated five times; medians of the seconds.
  {
    std::vector<double> seconds[3], error[3];
    for (int repeat = 0; repeat < 5; ++repeat)
      for (int k = 0; k < 3; ++k) {
        solo::PathTracerOptions s = o;
        s.min_samples = s.max_samples = 16;
        s.seed = 7;
        s.one_shadow_ray = k != 1;
        s.solid_angle_emitter_sampling = k != 2;
        const solo::RenderOutput out = solo::renderPathTraced(scene, s);
        seconds[k].push_back(out.report.seconds);
        error[k].push_back(relativeRmse(out.radiance, reference.radiance, reference.emitter_coverage));
      }
    std::printf("next-event estimation, 16 spp, median of 5: default %.3f s (relative RMSE %.4f), a shadow ray per light "
                "%.3f s (%.4f), emitters by area %.3f s (%.4f): default/per-light time %.3f, default/area time %.3f\n",
                median(seconds[0]), error[0][0], median(seconds[1]), error[1][0], median(seconds[2]), error[2][0],
                median(seconds[0]) / median(seconds[1]), median(seconds[0]) / median(seconds[2]));
  }

  // Adaptive sampling (relative error 5 %, 16 to 256 samples): the per-pixel threshold rule
  // with the Sobol sampler's error estimate from 1 replicate (sample variance / n, which assumes
  // independent samples), 2 replicates per pixel, 2 or 4 with the tile-pooled gain, and with the
  // independent sampler; then the image-error rule (the default) with each sampler.
  {
    struct Row {
      solo::SamplerKind sampler;
      int replicates;
      bool pooled;
    };
    for (const Row& row : {Row{solo::SamplerKind::Sobol, 1, true}, Row{solo::SamplerKind::Sobol, 2, false},
                           Row{solo::SamplerKind::Sobol, 2, true}, Row{solo::SamplerKind::Sobol, 4, true},
                           Row{solo::SamplerKind::Independent, 1, true}}) {
      solo::PathTracerOptions a = o;
      a.min_samples = 16;
      a.max_samples = 256;
      a.relative_error = 0.05;
      a.seed = 7;
      a.sampler = row.sampler;
      a.error_replicates = row.replicates;
      a.pool_error_gain = row.pooled;
      a.adaptive_rule = solo::AdaptiveRule::PixelThreshold;
      const solo::RenderOutput out = solo::renderPathTraced(scene, a);
      std::printf("adaptive 5 %%, per-pixel threshold, %s, %d replicate(s)%s: %.1f spp mean, %.2f s, relative RMSE %.4f\n",
                  solo::samplerKindName(row.sampler), row.replicates,
                  row.replicates == 1 ? "" : row.pooled ? ", tile-pooled gain" : ", per pixel",
                  std::get<double>(*out.report.find("samples_per_pixel_mean")), out.report.seconds,
                  relativeRmse(out.radiance, reference.radiance, reference.emitter_coverage));
    }
    for (const solo::SamplerKind kind : {solo::SamplerKind::Sobol, solo::SamplerKind::Independent}) {
      solo::PathTracerOptions a = o;
      a.min_samples = 16;
      a.max_samples = 256;
      a.relative_error = 0.05;
      a.seed = 7;
      a.sampler = kind;
      const solo::RenderOutput out = solo::renderPathTraced(scene, a);
      const double spp = std::get<double>(*out.report.find("samples_per_pixel_mean")) +
                         std::get<double>(*out.report.find("pilot_samples_per_pixel"));
      std::printf("adaptive 5 %%, image-error rule, %s: %.1f spp mean (pilot included), %.2f s, relative RMSE %.4f\n",
                  solo::samplerKindName(kind), spp, out.report.seconds,
                  relativeRmse(out.radiance, reference.radiance, reference.emitter_coverage));
    }
  }

  std::FILE* csv = argc > 3 ? std::fopen(argv[3], "w") : nullptr;
  if (csv) std::fprintf(csv, "sampler,spp,seconds,relative_rmse\n");
  std::printf("%-10s %6s %9s %14s\n", "sampler", "spp", "seconds", "relative_rmse");
  for (auto kind : {solo::LightSamplerKind::Uniform, solo::LightSamplerKind::Power, solo::LightSamplerKind::Hierarchy})
    for (int spp : {1, 4, 16, 64}) {
      o.light_sampler = kind;
      o.min_samples = o.max_samples = spp;
      o.seed = 7;
      solo::Stopwatch clock;
      const solo::RenderOutput out = solo::renderPathTraced(scene, o);
      const double seconds = clock.seconds();
      const double error = relativeRmse(out.radiance, reference.radiance, reference.emitter_coverage);
      std::printf("%-10s %6d %9.3f %14.4f\n", solo::lightSamplerName(kind), spp, seconds, error);
      if (csv) std::fprintf(csv, "%s,%d,%.4f,%.5f\n", solo::lightSamplerName(kind), spp, seconds, error);
    }
  if (csv) std::fclose(csv);
  return 0;
}
