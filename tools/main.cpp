// solo: one binary, one subcommand per job. This is the only file that sees CLI11;
// each subcommand fills an options struct (commands.h) and calls its run function.

#include "commands.h"

#include <solo/geometry/error.h>

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char** argv) {
  using namespace solo::tools;
  CLI::App app{"solo: turns a daytime street photo into a physically based night image"};
  app.require_subcommand(1);
  app.set_version_flag("--version", [] { return versionText(); }, "Print solo's version and its libraries' versions");

  InfoOptions info;
  CLI::App* info_cmd = app.add_subcommand("info", "Load and validate a scene; print what was read");
  info_cmd->add_option("scene", info.scene, "Scene manifest (JSON)")->required();
  info_cmd->add_flag("--json", info.json, "Print the input report as JSON");

  NightOptions night;
  CLI::App* night_cmd = app.add_subcommand("night", "Convert a day scene to night (default: the embedded scene)");
  night_cmd->add_option("scene", night.scene, "Scene manifest (JSON); omit for the embedded default scene");
  night_cmd->add_option("-o,--output", night.output, "Night image to write")->capture_default_str();
  night_cmd->add_option("--report", night.report, "Report JSON to write (default: <output>.report.json)");
  night_cmd->add_option("--seed", night.seed, "Random seed")->capture_default_str();

  ConvertOptions convert;
  CLI::App* convert_cmd = app.add_subcommand("convert", "Convert a depth or normal map between formats");
  convert_cmd->add_option("kind", convert.kind, "depth or normals")->required()->check(CLI::IsMember({"depth", "normals"}));
  convert_cmd->add_option("input", convert.input, "Input map (PNG, EXR, TIFF, PFM, NPY)")->required();
  convert_cmd->add_option("output", convert.output, "Output map; format from the extension")->required();
  convert_cmd->add_option("--input-scale", convert.input_scale_m_per_unit, "Metres per unit of an integer depth input");
  convert_cmd->add_option("--output-scale", convert.output_scale_m_per_unit, "Metres per unit of a 16-bit PNG depth output")
      ->capture_default_str();

  CLI11_PARSE(app, argc, argv);
  try {
    if (info_cmd->parsed()) return runInfo(info);
    if (night_cmd->parsed()) return runNight(night);
    if (convert_cmd->parsed()) return runConvert(convert);
  } catch (const solo::InputError& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "solo: error: " << e.what() << "\n";
    return 1;
  }
  return 1;
}
