#include "solo/core/atomic_file.h"

#include "solo/core/error.h"

#include <atomic>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace solo {

void writeAtomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path folder = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder, "cannot create output folder: " + ec.message());
  // Hidden, unique per process and call, same extension so writers pick the same format.
  const fs::path temporary = folder / ("." + target.stem().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                                       std::to_string(counter++) + target.extension().string());
  try {
    write(temporary);
  } catch (const InputError& e) {
    fs::remove(temporary, ec);
    // The user knows the target, not the hidden temporary: name the target.
    if (e.file() == temporary) throw InputError(target, e.problem());
    throw;
  } catch (...) {
    fs::remove(temporary, ec);
    throw;
  }
  fs::rename(temporary, target, ec);
  if (ec) {
    std::error_code ignore;
    fs::remove(temporary, ignore);
    throw InputError(target, "cannot move the finished file into place: " + ec.message());
  }
}

void writeTextAtomically(const fs::path& target, const std::string& text) {
  writeAtomically(target, [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(target, "cannot open for writing");
    out << text;
    out.close();
    if (!out) throw InputError(target, "write failed");
  });
}

}  // namespace solo
