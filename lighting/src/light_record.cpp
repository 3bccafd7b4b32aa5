#include "solo/lighting/light_record.h"

#include "solo/lighting/light_priors.h"

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/input_file.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace solo {

namespace {

using nlohmann::json;
using nlohmann::ordered_json;

constexpr const char* kFormat = "solo-lights/1";

ordered_json vector3(const Eigen::Vector3d& v) { return ordered_json::array({v.x(), v.y(), v.z()}); }
ordered_json rect(const cv::Rect& r) { return ordered_json::array({r.x, r.y, r.width, r.height}); }

/// Typed access with errors that name the file and where.
class Reader {
 public:
  Reader(const std::filesystem::path& file) : file_(file) {}
  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    throw InputError(file_, where + problem);
  }
  const json& field(const json& object, const char* key, const std::string& where) const {
    if (!object.is_object() || !object.contains(key)) fail(where, std::string("missing \"") + key + "\"");
    return object.at(key);
  }
  double number(const json& object, const char* key, const std::string& where) const {
    const json& v = field(object, key, where);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(where, std::string("\"") + key + "\" must be a number");
    return v.get<double>();
  }
  std::int64_t integer(const json& object, const char* key, const std::string& where) const {
    const json& v = field(object, key, where);
    if (!v.is_number_integer()) fail(where, std::string("\"") + key + "\" must be an integer");
    return v.get<std::int64_t>();
  }
  bool boolean(const json& object, const char* key, const std::string& where) const {
    const json& v = field(object, key, where);
    if (!v.is_boolean()) fail(where, std::string("\"") + key + "\" must be true or false");
    return v.get<bool>();
  }
  std::string text(const json& object, const char* key, const std::string& where) const {
    const json& v = field(object, key, where);
    if (!v.is_string()) fail(where, std::string("\"") + key + "\" must be a string");
    return v.get<std::string>();
  }
  Eigen::Vector3d vector(const json& object, const char* key, const std::string& where) const {
    const json& v = field(object, key, where);
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      fail(where, std::string("\"") + key + "\" must be 3 numbers");
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  }

 private:
  std::filesystem::path file_;
};

}  // namespace

std::string lightRecordJson(const LightRecord& record) {
  ordered_json j;
  j["format"] = kFormat;
  j["scene"] = record.scene;
  j["seed"] = record.seed;
  j["mode"] = record.ablation ? "ablation" : "sampled";
  j["illuminant_table"] = record.illuminant_table;
  j["image"] = {{"width", record.tree.width}, {"height", record.tree.height}};
  j["units"] = {{"chromaticity", "CIE 1931 2-degree xy; white = E (1/3, 1/3)"},
                {"strength", "cd/m2: luminance of the emitting surface; lm: luminous flux of the light"},
                {"centroid_m", "camera frame, x right, y down, z forward, metres"},
                {"area_m2", "emitting surface seen by the light's pixels, square metres"},
                {"pixels_off_depth", "pixels whose depth lies off the light's (its silhouette's mixed pixels): not in "
                                     "area_m2 nor centroid_m"},
                {"runs", "[row, first column, last column] of the light's pixels"}};
  ordered_json groups = ordered_json::array();
  for (const LightGroup& g : record.tree.groups) {
    ordered_json o;
    o["id"] = g.id;
    o["kind"] = lightGroupKindName(g.kind);
    o["source_id"] = g.source_id;
    o["bbox"] = rect(g.bbox);
    o["lights"] = g.lights;
    groups.push_back(o);
  }
  j["groups"] = groups;
  ordered_json draws = ordered_json::array();
  for (const GroupDraw& d : record.instantiation.draws) {
    ordered_json o;
    o["group"] = d.group;
    if (d.light) o["light"] = d.light;
    o["category"] = lightCategoryName(d.category);
    o["activation"] = d.activation;
    o["sample"] = d.sample;
    o["x"] = d.xy.x();
    o["y"] = d.xy.y();
    o["strength"] = d.strength;
    draws.push_back(o);
  }
  j["draws"] = draws;
  ordered_json lights = ordered_json::array();
  for (std::size_t i = 0; i < record.tree.lights.size(); ++i) {
    const Light& l = record.tree.lights[i];
    const LightState& s = record.instantiation.lights[i];
    const LightGeometry& g = record.geometry[i];
    ordered_json o;
    o["id"] = l.id;
    o["map_id"] = l.map_id;
    o["component"] = l.component;
    o["category"] = lightCategoryName(l.category);
    o["group"] = l.group;
    o["on"] = s.on;
    o["emits"] = s.emits;
    o["activation"] = s.activation;
    o["x"] = s.xy.x();
    o["y"] = s.xy.y();
    o["strength"] = s.strength;
    o["strength_unit"] = strengthUnitName(s.unit);
    o["emission_profile"] = emissionProfileName(emissionProfile(l.category));
    o["colour_source"] = s.colour_source;
    o["pixels"] = l.pixels;
    o["pixels_with_depth"] = g.pixels_with_depth;
    o["pixels_off_depth"] = g.pixels_off_depth;
    o["area_m2"] = g.area_m2;
    o["centroid_m"] = vector3(g.centroid_m);
    o["normal"] = vector3(g.normal);
    o["normal_source"] = normalSourceName(g.normal_source);
    o["placement"] = lightPlacementName(g.placement);
    o["implausible"] = lightPriorCheckNames(g.implausible);
    o["bbox"] = rect(l.bbox);
    ordered_json runs = ordered_json::array();
    for (const PixelRun& r : l.runs) runs.push_back(ordered_json::array({r.row, r.first_col, r.last_col}));
    o["runs"] = runs;
    lights.push_back(o);
  }
  j["lights"] = lights;
  return j.dump(1) + "\n";
}

void writeLightRecord(const std::filesystem::path& file, const LightRecord& record) {
  writeTextAtomically(file, lightRecordJson(record));
}

namespace {

// The header: format, provenance and the image size the pixel runs refer to.
void readHeader(const json& j, const Reader& r, LightRecord& record) {
  if (!j.is_object() || !j.contains("format") || j["format"] != kFormat)
    r.fail("", std::string("not a light record (expected \"format\": \"") + kFormat + "\")");
  record.scene = j.value("scene", "");
  record.seed = j.value("seed", std::uint64_t{0});
  record.ablation = j.value("mode", "sampled") == "ablation";
  record.illuminant_table = j.value("illuminant_table", "");
  const json& image = r.field(j, "image", "");
  record.tree.width = static_cast<int>(r.integer(image, "width", "image: "));
  record.tree.height = static_cast<int>(r.integer(image, "height", "image: "));
  if (record.tree.width <= 0 || record.tree.height <= 0) r.fail("image: ", "width and height must be positive");
}

// The groups, ids 0, 1, 2, ... in order, group 0 the root; returns their ids.
std::set<int> readGroups(const json& j, const Reader& r, LightRecord& record) {
  const json& groups = r.field(j, "groups", "");
  if (!groups.is_array()) r.fail("", "\"groups\" must be an array");
  std::set<int> group_ids;
  for (std::size_t index = 0; index < groups.size(); ++index) {
    const json& o = groups[index];
    const std::string where = "group #" + std::to_string(index) + ": ";
    LightGroup g;
    g.id = static_cast<int>(r.integer(o, "id", where));
    try {
      g.kind = lightGroupKindFromName(r.text(o, "kind", where));
    } catch (const std::invalid_argument& e) {
      r.fail(where, e.what());
    }
    g.source_id = static_cast<int>(o.value("source_id", 0));
    if (o.contains("bbox") && o["bbox"].is_array() && o["bbox"].size() == 4)
      g.bbox = cv::Rect(o["bbox"][0].get<int>(), o["bbox"][1].get<int>(), o["bbox"][2].get<int>(), o["bbox"][3].get<int>());
    if (g.id != static_cast<int>(index)) r.fail(where, "group ids must be 0, 1, 2, ... in order (got " + std::to_string(g.id) + ")");
    if ((g.id == 0) != (g.kind == LightGroupKind::Root)) r.fail(where, "group 0, and only group 0, is the root");
    group_ids.insert(g.id);
    record.tree.groups.push_back(g);
  }
  if (record.tree.groups.empty()) r.fail("", "\"groups\" must hold at least the root");
  return group_ids;
}

// The light's pixel runs, each inside the width x height image; they also give its pixel
// count and bounding box.
void readRuns(const json& o, const Reader& r, const std::string& where, int width, int height, Light& l) {
  const json& runs = r.field(o, "runs", where);
  if (!runs.is_array() || runs.empty()) r.fail(where, "\"runs\" must be a non-empty array of [row, first, last]");
  for (const json& run : runs) {
    if (!run.is_array() || run.size() != 3 || !run[0].is_number_integer() || !run[1].is_number_integer() ||
        !run[2].is_number_integer())
      r.fail(where, "a pixel run must be [row, first column, last column]");
    const PixelRun p{run[0].get<int>(), run[1].get<int>(), run[2].get<int>()};
    if (p.row < 0 || p.row >= height || p.first_col < 0 || p.last_col >= width || p.first_col > p.last_col)
      r.fail(where, "pixel run [" + std::to_string(p.row) + ", " + std::to_string(p.first_col) + ", " +
                        std::to_string(p.last_col) + "] lies outside the " + std::to_string(width) + "x" +
                        std::to_string(height) + " image");
    l.runs.push_back(p);
    l.pixels += p.last_col - p.first_col + 1;
    const cv::Rect box(p.first_col, p.row, p.last_col - p.first_col + 1, 1);
    l.bbox = l.bbox.empty() ? box : (l.bbox | box);
  }
}

// The light's state: on, colour, strength and its unit.
LightState readLightState(const json& o, const Reader& r, const std::string& where, const std::filesystem::path& file) {
  LightState s;
  s.on = r.boolean(o, "on", where);
  s.emits = o.value("emits", true);
  s.activation = o.value("activation", 1.0);
  s.xy = {r.number(o, "x", where), r.number(o, "y", where)};
  validateChromaticity(s.xy, file, where);
  s.strength = r.number(o, "strength", where);
  if (s.strength < 0) r.fail(where, "negative strength");
  try {
    s.unit = strengthUnitFromName(r.text(o, "strength_unit", where));
  } catch (const std::invalid_argument& e) {
    r.fail(where, e.what());
  }
  s.colour_source = o.value("colour_source", "");
  return s;
}

// The light's geometry: pixels with depth, area, centroid and normal.
LightGeometry readLightGeometry(const json& o, const Reader& r, const std::string& where) {
  LightGeometry g;
  g.pixels_with_depth = o.value("pixels_with_depth", std::int64_t{0});
  g.pixels_off_depth = o.value("pixels_off_depth", std::int64_t{0});
  g.area_m2 = o.value("area_m2", 0.0);
  if (!std::isfinite(g.area_m2) || g.area_m2 < 0) r.fail(where, "\"area_m2\" must be a non-negative number");
  if (o.contains("centroid_m")) g.centroid_m = r.vector(o, "centroid_m", where);
  if (o.contains("normal")) g.normal = r.vector(o, "normal", where);
  try {
    g.normal_source = normalSourceFromName(o.value("normal_source", "facing_camera"));
    if (o.contains("placement")) g.placement = lightPlacementFromName(r.text(o, "placement", where));
    if (o.contains("implausible")) {
      const json& checks = o.at("implausible");
      if (!checks.is_array() || !std::all_of(checks.begin(), checks.end(), [](const json& c) { return c.is_string(); }))
        r.fail(where, "\"implausible\" must be an array of check names");
      g.implausible = lightPriorChecksFromNames(checks.get<std::vector<std::string>>());
    }
  } catch (const std::invalid_argument& e) {
    r.fail(where, e.what());
  }
  return g;
}

// The lights, each in an existing group that can hold its category, with unique positive ids.
void readLights(const json& j, const Reader& r, const std::set<int>& group_ids, const std::filesystem::path& file,
                LightRecord& record) {
  const int width = record.tree.width, height = record.tree.height;
  const json& lights = r.field(j, "lights", "");
  if (!lights.is_array()) r.fail("", "\"lights\" must be an array");
  std::set<int> light_ids;
  for (std::size_t index = 0; index < lights.size(); ++index) {
    const json& o = lights[index];
    Light l;
    l.id = static_cast<int>(r.integer(o, "id", "light #" + std::to_string(index) + ": "));
    const std::string where = "light " + std::to_string(l.id) + ": ";
    if (l.id <= 0 || !light_ids.insert(l.id).second) r.fail(where, "light ids must be positive and unique");
    l.map_id = static_cast<int>(o.value("map_id", 0));
    l.component = static_cast<int>(o.value("component", 0));
    try {
      l.category = lightCategoryFromName(r.text(o, "category", where));
    } catch (const std::invalid_argument& e) {
      r.fail(where, e.what());
    }
    l.group = static_cast<int>(r.integer(o, "group", where));
    if (!group_ids.count(l.group)) r.fail(where, "group " + std::to_string(l.group) + " does not exist");
    const LightGroupKind kind = record.tree.groups[l.group].kind;
    if (!activationBounds(kind, l.category))
      r.fail(where, std::string("a ") + lightGroupKindName(kind) + " group cannot hold a " + lightCategoryName(l.category) +
                        " light");
    const LightState s = readLightState(o, r, where, file);
    readRuns(o, r, where, width, height, l);
    const LightGeometry g = readLightGeometry(o, r, where);
    record.tree.groups[l.group].lights.push_back(l.id);
    record.tree.lights.push_back(std::move(l));
    record.instantiation.lights.push_back(s);
    record.geometry.push_back(g);
  }
}

// The group draws, when the record holds them (informative: nothing is checked).
void readDraws(const json& j, const Reader& r, LightRecord& record) {
  if (!j.contains("draws") || !j["draws"].is_array()) return;
  for (const json& o : j["draws"]) {
    GroupDraw d;
    d.group = o.value("group", 0);
    d.light = o.value("light", 0);
    try {
      d.category = lightCategoryFromName(o.value("category", ""));
    } catch (const std::invalid_argument& e) {
      r.fail("draws: ", e.what());
    }
    d.activation = o.value("activation", 0.0);
    d.sample = o.value("sample", -1);
    d.xy = {o.value("x", 1.0 / 3.0), o.value("y", 1.0 / 3.0)};
    d.strength = o.value("strength", 0.0);
    record.instantiation.draws.push_back(d);
  }
}

LightRecord recordFromJson(const json& j, const std::filesystem::path& file) {
  const Reader r(file);
  LightRecord record;
  readHeader(j, r, record);
  const std::set<int> group_ids = readGroups(j, r, record);
  readLights(j, r, group_ids, file, record);
  readDraws(j, r, record);
  return record;
}

}  // namespace

LightRecord readLightRecord(const std::filesystem::path& file) {
  requireRegularFile(file, "light record");
  std::ifstream in(file);
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number beyond a double
    throw InputError(file, std::string("malformed JSON: ") + e.what());
  }
  try {
    return recordFromJson(j, file);
  } catch (const json::exception& e) {
    throw InputError(file, std::string("a field has the wrong type: ") + e.what());
  }
}

}  // namespace solo
