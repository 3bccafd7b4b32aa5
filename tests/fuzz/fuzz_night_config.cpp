// libFuzzer target: the night config file (solo night --config FILE), read by CLI11's TOML/INI
// reader the way solo's main sets it up: the config on the main app, a [night] section falling
// through to the night command, unknown keys an error, and options of each kind the night
// command has (a choice, a seed, integers, numbers, flags, paths, a list). Every problem must
// come out as a CLI::ParseError, which solo turns into exit 2 naming the file.

#include "fuzz_support.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace {

struct NightKnobs {
  std::string preset = "default";
  std::uint64_t seed = 0;
  int min_spp = 4, max_spp = 64;
  double relative_error = 0.05, glare_threshold = -1;
  bool refine = true, sixteen_bit = false;
  std::string output = "night.png";
  std::optional<std::string> lights;
  std::vector<double> sensor_white;
};

int parseConfig(const std::filesystem::path& file) {
  NightKnobs knobs;
  CLI::App app{"solo"};
  app.require_subcommand(1);
  CLI::App* night = app.add_subcommand("night", "night");
  night->add_option("--preset", knobs.preset)->check(CLI::IsMember({"draft", "default", "final"}));
  night->add_option("--seed", knobs.seed);
  night->add_option("--min-spp", knobs.min_spp);
  night->add_option("--max-spp", knobs.max_spp);
  night->add_option("--relative-error", knobs.relative_error);
  night->add_option("--glare-threshold", knobs.glare_threshold);
  night->add_flag("--refine,!--no-refine", knobs.refine);
  night->add_flag("--16bit", knobs.sixteen_bit);
  night->add_option("-o,--output", knobs.output);
  night->add_option("--lights", knobs.lights);
  night->add_option("--sensor-white", knobs.sensor_white)->expected(3);
  app.set_config("--config", "", "config");
  app.allow_config_extras(CLI::config_extras_mode::error);
  night->fallthrough();
  const std::string path = file.string();
  std::vector<std::string> arguments = {path, "--config", "night"};  // CLI11 parses a reversed vector
  try {
    app.parse(arguments);
  } catch (const CLI::ParseError&) {
  }
  return 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return solo::fuzz::readInput(data, size, ".toml", parseConfig);
}
