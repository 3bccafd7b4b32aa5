#include "solo/synth/street_scene.h"

#include <solo/lighting/light_category.h>

#include <array>
#include <cmath>
#include <random>
#include <stdexcept>

namespace solo {
namespace {

// Cityscapes labelIds used by the generator (reference section 4).
enum Class : int {
  kRoad = 7, kSidewalk = 8, kBuilding = 11, kPole = 17, kTrafficLight = 19, kTrafficSign = 20,
  kTerrain = 22, kPerson = 24, kCar = 26, kTruck = 27, kBus = 28, kTrain = 31, kBicycle = 33,
};

constexpr double kGroundY = 1.5;  // road surface, metres below the camera
constexpr double kPi = 3.14159265358979323846;

using Colour = Eigen::Vector3f;
const Colour kGlass{0.04f, 0.05f, 0.06f};
const Colour kAsphalt{0.09f, 0.09f, 0.1f};
const Colour kPaint{0.7f, 0.7f, 0.68f};
const Colour kConcrete{0.3f, 0.29f, 0.27f};
const Colour kMetal{0.2f, 0.21f, 0.22f};
const Colour kRubber{0.03f, 0.03f, 0.03f};

struct Layout {
  double street_length = 200;  // road and sidewalks end here, metres along z
  double buildings_until = 150;
  bool far_buildings = true;
  bool tall_buildings = true;
  bool lights = true;
  double ground_half_width = 60;  // terrain beyond the street end, metres
  double parked_until = 90;       // parked vehicles along the kerbs up to here, metres
  bool moving_traffic = true;     // vehicles in the lanes (they hide the horizon)
};

class Builder {
 public:
  Builder(StreetScene& scene, std::uint64_t seed, bool lights) : scene_(scene), rng_(seed), lights_(lights) {}

  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  int uniformInt(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng_); }
  bool chance(double p) { return uniform(0, 1) < p; }
  template <class T>
  const T& pick(const std::vector<T>& items) {
    return items[static_cast<std::size_t>(uniformInt(0, static_cast<int>(items.size()) - 1))];
  }
  Colour jitter(const Colour& c, double amount) {
    return (c * static_cast<float>(uniform(1 - amount, 1 + amount))).cwiseMin(0.9f);
  }

  /// Box from x0..x1, heights h0..h1 above the road surface, z0..z1.
  ScenePart& box(double x0, double x1, double h0, double h1, double z0, double z1, int label, int instance,
                 const Colour& albedo, float roughness) {
    ScenePart part;
    part.box.min = {std::min(x0, x1), kGroundY - std::max(h0, h1), std::min(z0, z1)};
    part.box.max = {std::max(x0, x1), kGroundY - std::min(h0, h1), std::max(z0, z1)};
    part.label_id = label;
    part.instance_id = instance;
    part.albedo = albedo;
    part.roughness = roughness;
    scene_.parts.push_back(part);
    return scene_.parts.back();
  }

  int thing(int class_id) { return class_id * 1000 + next_instance_[class_id]++; }
  int light(LightCategory category) {
    if (!lights_) return 0;
    const int c = static_cast<int>(category);
    return c * 1000 + next_light_[c]++;
  }
  int group() { return lights_ ? next_group_++ : 0; }
  bool lights() const { return lights_; }

 private:
  StreetScene& scene_;
  std::mt19937_64 rng_;
  bool lights_;
  std::array<int, 40> next_instance_{};
  std::array<int, kLastLightCategory + 1> next_light_{};
  int next_group_ = 1;
};

// Street cross-section (x, metres): the camera drives in the right lane.
constexpr double kRightLaneMin = -1.75, kRightLaneMax = 1.75;
constexpr double kLeftLaneMin = -5.25;
constexpr double kRightParkingMax = 4.25, kLeftParkingMin = -7.75;
constexpr double kRightFacade = 7.25, kLeftFacade = -10.75;

void addGround(Builder& b, const Layout& layout) {
  const double end = layout.street_length;
  b.box(kLeftParkingMin, kRightParkingMax, -0.3, 0, -5, end, kRoad, kRoad, kAsphalt, 0.8f);
  b.box(kRightParkingMax, kRightFacade, -0.3, 0.15, -5, end, kSidewalk, kSidewalk, kConcrete, 0.7f);
  b.box(kLeftFacade, kLeftParkingMin, -0.3, 0.15, -5, end, kSidewalk, kSidewalk, kConcrete, 0.7f);
  // Dashed centre line: 3 m dashes every 9 m, 5 mm proud of the asphalt.
  for (double z = 2; z + 3 < end; z += 9)
    b.box(-1.85, -1.65, -0.01, 0.005, z, z + 3, kRoad, kRoad, kPaint, 0.6f);
  // Open ground beyond the street and between the buildings' backs.
  const double w = layout.ground_half_width;
  b.box(-w, w, -0.3, 0, end, end + (layout.far_buildings ? 40 : 300), kTerrain, kTerrain, Colour(0.12f, 0.16f, 0.07f),
        0.9f);
  b.box(kRightFacade, w, -0.3, 0, -5, end, kTerrain, kTerrain, Colour(0.12f, 0.16f, 0.07f), 0.9f);
  b.box(-w, kLeftFacade, -0.3, 0, -5, end, kTerrain, kTerrain, Colour(0.12f, 0.16f, 0.07f), 0.9f);
}

void addBuildingRow(Builder& b, const Layout& layout, bool right_side) {
  const std::vector<Colour> palette = {{0.55f, 0.45f, 0.33f}, {0.35f, 0.12f, 0.08f}, {0.6f, 0.6f, 0.58f},
                                       {0.3f, 0.3f, 0.32f},   {0.5f, 0.38f, 0.3f}};
  const double facade = right_side ? kRightFacade : kLeftFacade;
  const double outward = right_side ? 1 : -1;  // from the street into the building
  double z = -8;
  while (z < layout.buildings_until) {
    const double length = b.uniform(10, 26);
    const int floors = layout.tall_buildings ? b.uniformInt(3, 9) : 1;
    const double floor_height = 3.2;
    const double height = floors * floor_height + (layout.tall_buildings ? b.uniform(0.3, 1.5) : b.uniform(0.3, 1.2));
    const double depth = b.uniform(10, 16);
    const Colour wall = b.jitter(b.pick(palette), 0.15);
    b.box(facade, facade + outward * depth, 0, height, z, z + length, kBuilding, kBuilding, wall, 0.75f);
    // Windows: a grid per floor on the street facade, 6 cm proud of the wall.
    const int columns = static_cast<int>((length - 1.0) / 2.6);
    const double margin = (length - columns * 2.6) / 2;
    for (int f = 0; f < floors; ++f) {
      const int group = b.group();
      for (int c = 0; c < columns; ++c) {
        const double z0 = z + margin + c * 2.6 + 0.65;
        const double h0 = f * floor_height + 0.9;
        ScenePart& w = b.box(facade - outward * 0.06, facade + outward * 0.02, h0, h0 + 1.6, z0, z0 + 1.3, kBuilding,
                             kBuilding, b.jitter(kGlass, 0.3), 0.05f);
        w.light_id = b.light(LightCategory::WindowBuilding);
        w.group_id = w.light_id ? group : 0;
      }
    }
    z += length + (b.chance(0.3) ? b.uniform(2, 6) : 0);  // an occasional alley shows the sky
  }
}

void addFarBuildings(Builder& b, const Layout& layout) {
  const std::vector<Colour> palette = {{0.45f, 0.45f, 0.5f}, {0.5f, 0.42f, 0.35f}, {0.35f, 0.36f, 0.4f}};
  double x = -layout.ground_half_width;
  const double z0 = layout.street_length + 40;
  while (x < layout.ground_half_width) {
    const double width = b.uniform(12, 35);
    b.box(x, x + width, 0, b.uniform(20, 70), z0 + b.uniform(0, 15), z0 + 40, kBuilding, kBuilding,
          b.jitter(b.pick(palette), 0.1), 0.8f);
    x += width + (b.chance(0.25) ? b.uniform(3, 10) : 0);
  }
}

void addStreetLights(Builder& b, const Layout& layout) {
  const LightCategory cct = b.chance(0.5) ? LightCategory::StreetLightHighCct : LightCategory::StreetLightLowCct;
  for (int side = 0; side < 2; ++side) {
    const bool right = side == 0;
    const double pole_x = right ? 4.75 : -8.25;
    const double reach = right ? -1.6 : 1.6;  // arm toward the road
    for (double z = right ? 12 : 26; z < std::min(layout.street_length, 160.0); z += 28) {
      b.box(pole_x, pole_x + 0.16, 0.15, 8.0, z, z + 0.16, kPole, kPole, kMetal, 0.4f);
      b.box(pole_x + 0.08, pole_x + 0.08 + reach, 7.85, 8.0, z + 0.03, z + 0.13, kPole, kPole, kMetal, 0.4f);
      ScenePart& head = b.box(pole_x + 0.08 + reach - 0.4 * (right ? 1 : -1), pole_x + 0.08 + reach + 0.4 * (right ? 1 : -1),
                              7.7, 7.9, z - 0.17, z + 0.33, kPole, kPole, Colour(0.8f, 0.78f, 0.7f), 0.3f);
      head.light_id = b.light(cct);
    }
  }
}

void addTrafficLight(Builder& b) {
  const double z = 35;
  b.box(4.6, 4.76, 0.15, 3.2, z, z + 0.16, kPole, kPole, kMetal, 0.4f);
  b.box(4.5, 4.86, 3.2, 4.2, z, z + 0.3, kTrafficLight, kTrafficLight, Colour(0.05f, 0.05f, 0.05f), 0.5f);
  const int active = b.uniformInt(0, 2);  // red, orange, green
  const LightCategory categories[3] = {LightCategory::TrafficLightRed, LightCategory::TrafficLightOrange,
                                       LightCategory::TrafficLightGreen};
  const Colour lit[3] = {{0.8f, 0.05f, 0.03f}, {0.85f, 0.45f, 0.02f}, {0.05f, 0.7f, 0.2f}};
  for (int i = 0; i < 3; ++i) {
    const double h = 3.91 - 0.32 * i;
    ScenePart& lamp = b.box(4.56, 4.8, h, h + 0.24, z - 0.04, z, kTrafficLight, kTrafficLight,
                            i == active ? lit[i] : Colour(lit[i] * 0.15f), 0.2f);
    if (i == active) lamp.light_id = b.light(categories[i]);
  }
}

void addThinObjects(Builder& b) {
  // A sign on a 6 cm pole, a person-sized box, a bollard.
  b.box(5.0, 5.06, 0.15, 2.2, 20, 20.06, kPole, kPole, kMetal, 0.4f);
  b.box(4.73, 5.33, 2.2, 2.8, 19.98, 20.0, kTrafficSign, kTrafficSign, Colour(0.6f, 0.05f, 0.05f), 0.4f);
  b.box(5.6, 6.1, 0.15, 1.9, 14, 14.3, kPerson, b.thing(kPerson), Colour(0.2f, 0.15f, 0.12f), 0.8f);
  b.box(-8.4, -7.9, 0.15, 1.85, 18, 18.3, kPerson, b.thing(kPerson), Colour(0.1f, 0.12f, 0.2f), 0.8f);
  b.box(4.45, 4.6, 0.15, 1.1, 9, 9.15, kPole, kPole, kMetal, 0.4f);
}

struct VehicleSpec {
  int class_id;
  double width, length, body_height, cabin_height;
  bool parked;
  bool heading_away;  // +z: rear faces the camera
};

void addVehicle(Builder& b, const VehicleSpec& v, double x_center, double z0) {
  const std::vector<Colour> paints = {{0.7f, 0.7f, 0.7f}, {0.4f, 0.41f, 0.42f}, {0.03f, 0.03f, 0.035f},
                                      {0.45f, 0.05f, 0.04f}, {0.05f, 0.1f, 0.35f}, {0.5f, 0.45f, 0.3f}};
  const int id = b.thing(v.class_id);
  const Colour paint = b.pick(paints);
  const double x0 = x_center - v.width / 2, x1 = x_center + v.width / 2, z1 = z0 + v.length;
  const bool transport = v.class_id == kBus || v.class_id == kTrain;
  b.box(x0, x1, 0.3, v.body_height, z0, z1, v.class_id, id, paint, 0.3f);
  // Wheels.
  for (double wz : {z0 + 0.5, z1 - 1.1})
    for (double wx : {x0 + 0.05, x1 - 0.3}) b.box(wx, wx + 0.25, 0, 0.62, wz, wz + 0.6, v.class_id, id, kRubber, 0.9f);

  // Cabin (cars, trucks) with windows; buses and trams have window rows in the body.
  const LightCategory window_category = transport ? LightCategory::WindowTransport : LightCategory::WindowParked;
  const bool windows_are_lights = transport || v.parked;
  if (!transport && v.cabin_height > 0) {
    const double c0 = v.class_id == kTruck ? (v.heading_away ? z1 - 2.2 : z0) : z0 + 0.3 * v.length;
    const double c1 = v.class_id == kTruck ? c0 + 2.2 : z0 + 0.78 * v.length;
    const double top = v.body_height + v.cabin_height;
    b.box(x0 + 0.1, x1 - 0.1, v.body_height, top, c0, c1, v.class_id, id, paint, 0.3f);
    for (double side : {x0 + 0.08, x1 - 0.12}) {
      ScenePart& w = b.box(side, side + 0.04, v.body_height + 0.08, top - 0.06, c0 + 0.2, c1 - 0.2, v.class_id, id,
                           kGlass, 0.05f);
      if (windows_are_lights) w.light_id = b.light(window_category);
    }
    for (double face : {c0 - 0.02, c1 - 0.02}) {
      ScenePart& w = b.box(x0 + 0.25, x1 - 0.25, v.body_height + 0.06, top - 0.06, face, face + 0.04, v.class_id, id,
                           kGlass, 0.05f);
      if (windows_are_lights) w.light_id = b.light(window_category);
    }
  } else if (transport) {
    for (double side : {x0 - 0.02, x1 - 0.02})
      for (double wz = z0 + 1.0; wz + 1.4 < z1 - 0.6; wz += 1.8) {
        ScenePart& w = b.box(side, side + 0.04, 1.3, v.body_height - 0.4, wz, wz + 1.4, v.class_id, id, kGlass, 0.05f);
        w.light_id = b.light(window_category);
      }
  }

  // Front and rear lights, 3 cm proud of the body's ends.
  const double front = v.heading_away ? z1 : z0;
  const double rear = v.heading_away ? z0 : z1;
  const double out = v.heading_away ? 1 : -1;
  const LightCategory front_category = v.parked ? LightCategory::ParkedFront : LightCategory::MovingFront;
  const LightCategory rear_category = v.parked ? LightCategory::ParkedRear : LightCategory::MovingRear;
  if (v.class_id == kBicycle) {
    ScenePart& f = b.box(x0 - 0.02, x1 + 0.02, 0.9, 1.0, front, front + out * 0.05, v.class_id, id, kPaint, 0.3f);
    f.light_id = b.light(front_category);
    ScenePart& r = b.box(x0 - 0.02, x1 + 0.02, 0.8, 0.88, rear, rear - out * 0.05, v.class_id, id,
                         Colour(0.5f, 0.03f, 0.03f), 0.3f);
    r.light_id = b.light(rear_category);
    return;
  }
  for (double lx : {x0 + 0.1, x1 - 0.45}) {
    ScenePart& f = b.box(lx, lx + 0.35, 0.7, 0.85, front, front + out * 0.03, v.class_id, id, kPaint, 0.2f);
    f.light_id = b.light(front_category);
    ScenePart& r = b.box(lx, lx + 0.35, 0.8, 0.95, rear, rear - out * 0.03, v.class_id, id,
                         Colour(0.45f, 0.03f, 0.02f), 0.2f);
    r.light_id = b.light(rear_category);
  }
}

void addVehicles(Builder& b, const Layout& layout) {
  const VehicleSpec car{kCar, 1.8, 4.4, 1.1, 0.45, true, true};
  // Parked cars along both kerbs, some facing each way.
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? (kRightLaneMax + kRightParkingMax) / 2 + 0.1 : (kLeftParkingMin + kLeftLaneMin) / 2;
    double z = side == 0 ? 7 : 9;
    while (z < std::min(layout.parked_until, layout.street_length - 10)) {
      VehicleSpec spec = car;
      spec.heading_away = b.chance(0.5);
      if (side == 0 && z > 24 && z < 40) {
        spec = {kTruck, 2.4, 7.0, 3.2, 0.0, true, true};  // a parked truck, cab included in the box
        spec.cabin_height = 0;
      }
      addVehicle(b, spec, x, z);
      z += spec.length + b.uniform(1.0, 6.0);
    }
  }
  // A bicycle parked at the kerb in front of the first parked car.
  addVehicle(b, {kBicycle, 0.08, 1.7, 1.05, 0, true, true}, kRightParkingMax - 0.2, 4.0);
  if (!layout.moving_traffic) return;
  // Moving traffic: one car ahead in our lane, one oncoming, a bus or a tram oncoming further away.
  addVehicle(b, {kCar, 1.8, 4.4, 1.1, 0.45, false, true}, 0.0, b.uniform(18, 26));
  addVehicle(b, {kCar, 1.8, 4.5, 1.1, 0.45, false, false}, (kLeftLaneMin + kRightLaneMin) / 2, b.uniform(28, 36));
  const bool tram = b.chance(0.5);
  addVehicle(b, {tram ? kTrain : kBus, 2.5, tram ? 20.0 : 12.0, 3.2, 0, false, false}, (kLeftLaneMin + kRightLaneMin) / 2,
             b.uniform(55, 70));
}

}  // namespace

const char* streetVariantName(StreetVariant v) {
  switch (v) {
    case StreetVariant::Default: return "default";
    case StreetVariant::Grazing: return "grazing";
    case StreetVariant::ThinPole: return "thin-pole";
    case StreetVariant::NearObject: return "near-object";
    case StreetVariant::WideSky: return "wide-sky";
    case StreetVariant::NoLights: return "no-lights";
  }
  return "default";
}

StreetVariant streetVariantFromName(const std::string& name) {
  for (StreetVariant v : {StreetVariant::Default, StreetVariant::Grazing, StreetVariant::ThinPole,
                          StreetVariant::NearObject, StreetVariant::WideSky, StreetVariant::NoLights})
    if (name == streetVariantName(v)) return v;
  throw std::invalid_argument("unknown scene variant \"" + name +
                              "\" (default, grazing, thin-pole, near-object, wide-sky, no-lights)");
}

StreetScene buildStreetScene(const StreetSceneOptions& options) {
  if (options.width < 16 || options.height < 16)
    throw std::invalid_argument("synthetic scene size must be at least 16x16 pixels");
  StreetScene scene;
  scene.options = options;
  scene.camera = PinholeCamera::acdc().scaledTo(options.width, options.height);

  Layout layout;
  switch (options.variant) {
    case StreetVariant::Grazing:
      layout.street_length = 500;
      layout.buildings_until = 50;
      layout.far_buildings = false;
      layout.ground_half_width = 250;
      layout.parked_until = 40;
      layout.moving_traffic = false;
      break;
    case StreetVariant::WideSky:
      layout.tall_buildings = false;
      layout.far_buildings = false;
      break;
    case StreetVariant::NoLights: layout.lights = false; break;
    default: break;
  }

  Builder b(scene, options.seed, layout.lights);
  const double elevation = b.uniform(25, 55) * kPi / 180;
  const double azimuth = (b.chance(0.5) ? 1 : -1) * b.uniform(100, 150) * kPi / 180;
  scene.sun_direction = {std::cos(elevation) * std::sin(azimuth), -std::sin(elevation),
                         std::cos(elevation) * std::cos(azimuth)};

  addGround(b, layout);
  addBuildingRow(b, layout, true);
  addBuildingRow(b, layout, false);
  if (layout.far_buildings) addFarBuildings(b, layout);
  // Without lights (NoLights) the street furniture is the same; the builder hands out no light ids.
  addStreetLights(b, layout);
  addTrafficLight(b);
  addThinObjects(b);
  addVehicles(b, layout);

  if (options.variant == StreetVariant::ThinPole)
    b.box(0.6, 0.65, 0, 4.0, 3.0, 3.05, kPole, kPole, kMetal, 0.4f);
  if (options.variant == StreetVariant::NearObject)
    b.box(0.2, 0.7, 0, 1.6, 0.6, 0.9, kPerson, b.thing(kPerson), Colour(0.25f, 0.2f, 0.15f), 0.8f);
  return scene;
}

TriangleMesh streetSceneMesh(const StreetScene& scene) {
  TriangleMesh mesh;
  mesh.vertices.reserve(scene.parts.size() * 8);
  mesh.faces.reserve(scene.parts.size() * 12);
  // Corner c has bit 0 = x max, bit 1 = y max, bit 2 = z max. Quads listed counter-clockwise
  // seen from outside: -x, +x, -y, +y, -z, +z.
  static const int quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const ScenePart& part : scene.parts) {
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (int c = 0; c < 8; ++c)
      mesh.vertices.emplace_back(c & 1 ? part.box.max.x() : part.box.min.x(), c & 2 ? part.box.max.y() : part.box.min.y(),
                                 c & 4 ? part.box.max.z() : part.box.min.z());
    for (const auto& q : quads) {
      mesh.faces.push_back({base + q[0], base + q[1], base + q[2]});
      mesh.faces.push_back({base + q[0], base + q[2], base + q[3]});
    }
  }
  return mesh;
}

}  // namespace solo
