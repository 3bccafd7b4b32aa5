#include "commands.h"

#include <solo/core/version.h>

#include <CLI/Version.hpp>

#include <sstream>

namespace solo::tools {

std::vector<std::pair<std::string, std::string>> dependencyVersions() {
  auto list = pipelineDependencyVersions();
  list.push_back({"CLI11", CLI11_VERSION});
  return list;
}

std::string versionText() {
  std::ostringstream out;
  out << "solo " << soloVersion() << "\nbuilt against:\n";
  for (const auto& [name, version] : dependencyVersions()) out << "  " << name << " " << version << "\n";
  return out.str();
}

}  // namespace solo::tools
