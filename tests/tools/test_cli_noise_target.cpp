// `solo night --noise-target`: the exposure is metered on a preview before the render, the
// render stops at the sensor-noise target and reports how many pixels reached it, and the
// post-process uses the exposure the target was set for.

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <string>

#include "test_support.h"

using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;

namespace {

std::string q(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

const nlohmann::json& stage(const nlohmann::json& report, const std::string& name) {
  for (const auto& s : report["stages"])
    if (s["name"] == name) return s;
  throw std::runtime_error("no stage " + name);
}

std::string noteStartingWith(const nlohmann::json& s, const std::string& prefix) {
  for (const auto& n : s["notes"])
    if (n.get<std::string>().rfind(prefix, 0) == 0) return n.get<std::string>();
  return {};
}

double metric(const nlohmann::json& s, const std::string& name) {
  const auto& m = s["metrics"][name];
  return m.is_object() ? m["value"].get<double>() : m.get<double>();
}

}  // namespace

TEST(NightNoiseTarget, MetersAPreviewStopsAtTheSensorNoiseAndReportsTheShareReached) {
  TempDir dir;
  const auto synth = runSolo("synth -o " + q(dir / "street") + " --size 128x72 --seed 3");
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string base =
      "night " + q(dir / "street" / "scene.json") + " --no-optimize --no-solids --min-spp 4 --max-spp 8";

  const auto r = runSolo(base + " --noise-target -o " + q(dir / "n.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto report = nlohmann::json::parse(readText(dir / "n.report.json"));
  const auto& render = stage(report, "render");
  EXPECT_EQ(metric(render, "noise_factor"), 1.0);
  const double below = metric(render, "pixels_below_noise_target");
  EXPECT_GT(below, 0.0);
  EXPECT_LE(below, 1.0);
  // The note names the preview (a quarter of 128x72, at kMeteringSamplesPerPixel) and the
  // sensor white it metered, which is the one the post-process used.
  const std::string note =
      noteStartingWith(render, "noise-matched target: standard error <= 1.00 x sensor noise sigma");
  ASSERT_FALSE(note.empty()) << render.dump(2);
  EXPECT_NE(note.find("preview at 32 spp"), std::string::npos) << note;
  EXPECT_NE(note.find("32x18"), std::string::npos) << note;
  const auto at = note.find("sensor white ");
  ASSERT_NE(at, std::string::npos);
  const double metered = std::strtod(note.c_str() + at + 13, nullptr);
  EXPECT_NE(note.find("night camera metered a mean"), std::string::npos) << note;
  EXPECT_NEAR(metric(stage(report, "post"), "sensor_white"), metered, 1e-5 * metered);
  // The preview's samples are its own: another min-spp meters the very same exposure.
  const auto fewer = runSolo("night " + q(dir / "street" / "scene.json") +
                             " --no-optimize --no-solids --min-spp 2 --max-spp 8 --noise-target -o " + q(dir / "f.png"));
  ASSERT_EQ(fewer.exit_code, 0) << fewer.output;
  EXPECT_EQ(metric(stage(nlohmann::json::parse(readText(dir / "f.report.json")), "post"), "sensor_white"),
            metric(stage(report, "post"), "sensor_white"));

  // A given sensor white needs no preview; with the sensor noise off the target cannot apply.
  const auto given = runSolo(base + " --noise-target --sensor-white 5 -o " + q(dir / "g.png"));
  ASSERT_EQ(given.exit_code, 0) << given.output;
  const auto given_report = nlohmann::json::parse(readText(dir / "g.report.json"));
  EXPECT_FALSE(noteStartingWith(stage(given_report, "render"), "noise-matched target").empty());
  EXPECT_NE(noteStartingWith(stage(given_report, "render"), "noise-matched target").find("sensor white given, 5 cd/m2"),
            std::string::npos);
  EXPECT_EQ(metric(stage(given_report, "post"), "sensor_white"), 5.0);
  const auto quiet = runSolo(base + " --noise-target --no-noise -o " + q(dir / "q.png"));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  const auto quiet_report = nlohmann::json::parse(readText(dir / "q.report.json"));
  EXPECT_FALSE(noteStartingWith(stage(quiet_report, "render"), "noise-matched target skipped").empty());
  EXPECT_FALSE(stage(quiet_report, "render")["metrics"].contains("pixels_below_noise_target"));

  // The default preset matches the sensor noise; --no-noise-target goes back to the relative error.
  const auto plain = runSolo(base + " --no-noise-target -o " + q(dir / "p.png"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const auto plain_report = nlohmann::json::parse(readText(dir / "p.report.json"));
  EXPECT_TRUE(noteStartingWith(stage(plain_report, "render"), "noise-matched target").empty());
  // Without the noise target the exposure still comes from the preview, not from the render's
  // own few samples: the same sensor white.
  EXPECT_FALSE(noteStartingWith(stage(plain_report, "render"), "night camera metered a mean").empty())
      << stage(plain_report, "render").dump(2);
  EXPECT_EQ(metric(stage(plain_report, "post"), "sensor_white"), metric(stage(report, "post"), "sensor_white"));
  EXPECT_FALSE(stage(plain_report, "render")["metrics"].contains("pixels_below_noise_target"));
  const auto by_default = runSolo(base + " -o " + q(dir / "d.png"));
  ASSERT_EQ(by_default.exit_code, 0) << by_default.output;
  const auto default_report = nlohmann::json::parse(readText(dir / "d.report.json"));
  EXPECT_FALSE(noteStartingWith(stage(default_report, "render"), "noise-matched target: standard error <= 1.00").empty());

  // Shadow-ray roulette (on in the default preset, 0.3 x the sensor noise at black): at a fixed
  // sample count the paths are the same with it and without (it draws no number), so the rays
  // it skipped are exactly the difference.
  const std::string fixed = "night " + q(dir / "street" / "scene.json") +
                            " --no-optimize --no-solids --min-spp 4 --max-spp 4 --noise-target --sensor-white 5";
  const auto with = runSolo(fixed + " -o " + q(dir / "w.png"));
  ASSERT_EQ(with.exit_code, 0) << with.output;
  const auto without = runSolo(fixed + " --shadow-roulette 0 -o " + q(dir / "o.png"));
  ASSERT_EQ(without.exit_code, 0) << without.output;
  const auto with_report = nlohmann::json::parse(readText(dir / "w.report.json"));
  const auto without_report = nlohmann::json::parse(readText(dir / "o.report.json"));
  const auto& with_render = stage(with_report, "render");
  const auto& without_render = stage(without_report, "render");
  const double skipped = metric(with_render, "shadow_rays_skipped");
  EXPECT_GT(skipped, 0.0);
  EXPECT_GT(metric(with_render, "shadow_roulette_threshold_y"), 0.0);
  EXPECT_EQ(metric(with_render, "rays") + skipped, metric(without_render, "rays"));
  EXPECT_FALSE(without_render["metrics"].contains("shadow_rays_skipped"));
  EXPECT_FALSE(noteStartingWith(with_render, "shadow-ray roulette: next-event contributions below").empty());
  const auto bad = runSolo(fixed + " --shadow-roulette 2 -o " + q(dir / "b.png"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("shadow-roulette"), std::string::npos) << bad.output;
}
