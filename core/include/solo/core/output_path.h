#pragma once
// Checks on output paths made before any work, so that an output never destroys data: not the
// working folder or one of its parents, never one of the run's own inputs.

#include <filesystem>
#include <string>
#include <vector>

namespace solo {

/// The file's extension with its dot, in lower case: "Night.PNG" gives ".png"; "" for none.
std::string lowercaseExtension(const std::filesystem::path& file);

/// `path` in lexically normal form without trailing separators: "out/" and "out//" become
/// "out", "a/b/.." becomes "a"; "/" stays "/".
std::filesystem::path withoutTrailingSeparators(const std::filesystem::path& path);

/// Throws InputError naming `option` and `folder` when `folder` (symbolic links resolved) is
/// the working folder, one of its parents, or the root: such a folder is never replaced.
void refuseWorkingFolderOrParent(const std::filesystem::path& folder, const std::string& option);

/// True when `a` and `b` name the same file: the same inode when both exist, else the same
/// path once made absolute with symbolic links resolved (std::filesystem::weakly_canonical).
bool samePath(const std::filesystem::path& a, const std::filesystem::path& b);

/// Throws InputError naming `option`, `output` and the clashing input when writing `output`
/// would overwrite one of `inputs` (compared with samePath).
void refuseOutputThatIsAnInput(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs,
                               const std::string& option);

}  // namespace solo
