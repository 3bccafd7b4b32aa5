#pragma once
// Quality presets of `solo night` and the text of its configuration file.
//
// A preset sets the knobs that trade accuracy for time (render samples and noise target, light
// sampler, the depth optimisation's iterations and tolerance, mesh evaluation, glare and
// noise); docs/presets.md has the table with each preset's measured time and accuracy. Any knob
// given explicitly (command line or config file) keeps its given value.

#include "commands.h"

#include <functional>
#include <string>
#include <vector>

namespace solo::tools {

/// "draft", "default", "final", fastest first.
const std::vector<std::string>& nightPresetNames();

/// Sets every knob of options.preset on `options`, except those for which `given(flag)` is
/// true (flag as on the command line, e.g. "--max-spp"). Throws InputError("--preset", ...)
/// for an unknown preset name.
void applyNightPreset(NightOptions& options, const std::function<bool(const std::string& flag)>& given);

/// The options as a config file `solo --config FILE night` (or `solo night --config FILE`)
/// reads back to the same options: TOML, one `key = value` per option under `[night]`, keys
/// the long option names without dashes. Unset optional paths and write_config are left out.
/// Throws InputError for a path holding both quote characters (TOML strings cannot hold it).
std::string nightConfigText(const NightOptions& options);

}  // namespace solo::tools
