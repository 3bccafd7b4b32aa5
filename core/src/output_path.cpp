#include "solo/core/output_path.h"

#include "solo/core/error.h"

#include <algorithm>
#include <cctype>
#include <system_error>

namespace fs = std::filesystem;

namespace solo {

std::string lowercaseExtension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}
namespace {

fs::path resolved(const fs::path& path) {
  std::error_code ec;
  fs::path absolute = fs::absolute(path, ec);
  if (ec) return path.lexically_normal();
  fs::path canonical = fs::weakly_canonical(absolute, ec);
  return withoutTrailingSeparators(ec ? absolute : canonical);
}

// True when every component of `prefix` starts `path` (component-wise, not character-wise).
bool isPrefixOf(const fs::path& prefix, const fs::path& path) {
  return std::mismatch(prefix.begin(), prefix.end(), path.begin(), path.end()).first == prefix.end();
}

}  // namespace

fs::path withoutTrailingSeparators(const fs::path& path) {
  fs::path normal = path.lexically_normal();
  if (normal.has_filename() || normal == normal.root_path()) return normal;
  return normal.parent_path();
}

void refuseWorkingFolderOrParent(const fs::path& folder, const std::string& option) {
  std::error_code ec;
  const fs::path working = fs::current_path(ec);
  if (ec) throw InputError(option, "cannot find the working folder: " + ec.message());
  const fs::path target = resolved(folder);
  if (target == target.root_path() || isPrefixOf(target, resolved(working)))
    throw InputError(option, "\"" + folder.string() + "\" is the working folder or one of its parents (" +
                                 target.string() + "); it is never replaced");
}

bool samePath(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  const bool same = fs::equivalent(a, b, ec);
  if (!ec) return same;
  return resolved(a) == resolved(b);
}

void refuseOutputThatIsAnInput(const fs::path& output, const std::vector<fs::path>& inputs, const std::string& option) {
  for (const fs::path& input : inputs)
    if (samePath(output, input))
      throw InputError(option, "\"" + output.string() + "\" is an input of this run (" + input.string() +
                                   "); writing it would overwrite that input");
}

}  // namespace solo
