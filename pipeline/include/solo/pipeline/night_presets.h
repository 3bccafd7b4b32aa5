#pragma once
// Quality presets of the night conversion.
//
// A preset sets the knobs that trade accuracy for time (render samples and noise target, light
// sampler, the depth optimisation's iterations and tolerance, mesh evaluation, glare and
// noise, downsampling, denoising); docs/presets.md has the table with each preset's measured
// time and accuracy. `default` is exactly NightConversionOptions' defaults.

#include <solo/pipeline/night_conversion.h>

#include <functional>
#include <string>
#include <vector>

namespace solo {

/// "draft", "default", "final", fastest first.
const std::vector<std::string>& nightPresetNames();

/// The knobs a preset sets, named as `solo night`'s long options without dashes
/// ("max-spp", "optimize", ...).
const std::vector<std::string>& nightPresetKnobs();

/// Sets every knob of `preset` on `options`, except those for which `keep(knob)` is true (a
/// value the user gave). Throws InputError("--preset", ...) for an unknown preset name.
void applyNightPreset(NightConversionOptions& options, const std::string& preset,
                      const std::function<bool(const std::string& knob)>& keep = {});

/// NightConversionOptions with `preset` applied.
NightConversionOptions nightPreset(const std::string& preset);

}  // namespace solo
