#pragma once
// The light record: the JSON file `solo lights` writes and the renderer reads, which a
// user may edit (switch lights on or off, change a colour or strength, delete a light) and
// feed back. Format "solo-lights/1", described field by field in docs/lighting.md.

#include "solo/lighting/light_geometry.h"
#include "solo/lighting/light_groups.h"
#include "solo/lighting/light_instantiation.h"

#include <cstdint>
#include <filesystem>
#include <string>

namespace solo {

struct LightRecord {
  std::string scene;             ///< the scene manifest it was made from
  std::uint64_t seed = 0;
  bool ablation = false;
  std::string illuminant_table;  ///< the table the colours came from
  /// Lights and groups. A record read back keeps the ids written in the file (a user may
  /// have deleted lights), so tree.lights[i].id need not be i + 1 there.
  LightGroupTree tree;
  std::vector<LightGeometry> geometry;  ///< per tree.lights
  LightInstantiation instantiation;     ///< per tree.lights, and the draws
};

/// The record as pretty-printed JSON.
std::string lightRecordJson(const LightRecord& record);
/// Writes it atomically.
void writeLightRecord(const std::filesystem::path& file, const LightRecord& record);

/// Reads and validates a record. Throws InputError naming the file and the light for
/// malformed JSON, a wrong format tag, an unknown category or group kind, a light in a
/// group that does not exist or cannot hold its category, a duplicate id, an impossible
/// chromaticity, a negative or non-finite strength, an unknown unit, or a pixel run
/// outside the image.
LightRecord readLightRecord(const std::filesystem::path& file);

}  // namespace solo
