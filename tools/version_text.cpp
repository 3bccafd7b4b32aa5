#include "commands.h"

#include <solo/core/version.h>
#include <solo/render/ray_caster.h>

#include <CLI/Version.hpp>
#include <nlohmann/json.hpp>

#include <sstream>

namespace solo::tools {

std::vector<std::pair<std::string, std::string>> dependencyVersions() {
  auto list = geometryDependencyVersions();
  for (auto& v : renderDependencyVersions()) list.push_back(v);
  list.push_back({"CLI11", CLI11_VERSION});
  list.push_back({"nlohmann_json", std::to_string(NLOHMANN_JSON_VERSION_MAJOR) + "." +
                                       std::to_string(NLOHMANN_JSON_VERSION_MINOR) + "." +
                                       std::to_string(NLOHMANN_JSON_VERSION_PATCH)});
  return list;
}

std::string versionText() {
  std::ostringstream out;
  out << "solo " << soloVersion() << "\nbuilt against:\n";
  for (const auto& [name, version] : dependencyVersions()) out << "  " << name << " " << version << "\n";
  return out.str();
}

}  // namespace solo::tools
