#include "solo/core/atomic_file.h"

#include "solo/core/error.h"

#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>

namespace fs = std::filesystem;

namespace solo {
namespace {

// The hidden temporaries being written right now, as plain C strings a signal handler can
// unlink without allocating. A slot is claimed, filled, then marked live; the handler only
// reads live slots.
constexpr int kTemporarySlots = 64;
constexpr std::size_t kTemporaryPathBytes = 4096;

constexpr int kTemporaryFolderDepth = 4;

struct LiveTemporary {
  std::atomic<bool> claimed{false};
  std::atomic<bool> live{false};
  bool folder = false;
  char path[kTemporaryPathBytes] = {};
};

LiveTemporary g_live_temporaries[kTemporarySlots];

// Claims a slot for `temporary` and marks it live; -1 when there is none free (more than
// kTemporarySlots at once, never in solo) or the path is too long: it goes unregistered.
int claimTemporarySlot(const fs::path& temporary, bool folder) {
  std::error_code ec;
  const std::string text = fs::absolute(temporary, ec).string();
  if (ec || text.size() >= kTemporaryPathBytes) return -1;
  for (int i = 0; i < kTemporarySlots; ++i) {
    bool expected = false;
    if (!g_live_temporaries[i].claimed.compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_live_temporaries[i].path, text.c_str(), text.size() + 1);
    g_live_temporaries[i].folder = folder;
    g_live_temporaries[i].live.store(true, std::memory_order_release);
    return i;
  }
  return -1;
}

void releaseTemporarySlot(int slot) {
  if (slot < 0) return;
  g_live_temporaries[slot].live.store(false, std::memory_order_release);
  g_live_temporaries[slot].claimed.store(false, std::memory_order_release);
}

// Registers a temporary file with the signal handler for as long as it exists.
class TemporaryRegistration {
 public:
  explicit TemporaryRegistration(const fs::path& temporary) : slot_(claimTemporarySlot(temporary, false)) {}
  ~TemporaryRegistration() { releaseTemporarySlot(slot_); }
  TemporaryRegistration(const TemporaryRegistration&) = delete;
  TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;

 private:
  int slot_;
};

bool isDotOrDotDot(const char* name) { return name[0] == '.' && (name[1] == 0 || (name[1] == '.' && name[2] == 0)); }

// Removes what the open folder `folder_fd` holds, `depth` levels of subfolders at most, with
// system calls only (no allocation, no stdio): a signal handler may call it. Entries removed
// while the folder is read can make getdents64 skip others, so it reads the folder again from
// the start until a pass finds nothing left (a few passes at most).
void removeFolderContents(int folder_fd, int depth) noexcept {
  alignas(8) char buffer[4096];
  for (int pass = 0; pass < 8; ++pass) {
    if (::lseek(folder_fd, 0, SEEK_SET) < 0) return;
    bool found = false;
    for (ssize_t bytes; (bytes = ::getdents64(folder_fd, buffer, sizeof buffer)) > 0;) {
      for (ssize_t offset = 0; offset < bytes;) {
        const auto* entry = reinterpret_cast<const struct dirent64*>(buffer + offset);
        offset += entry->d_reclen;
        if (isDotOrDotDot(entry->d_name)) continue;
        found = true;
        if (::unlinkat(folder_fd, entry->d_name, 0) == 0 || depth == 0) continue;
        const int child = ::openat(folder_fd, entry->d_name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
        if (child < 0) continue;
        removeFolderContents(child, depth - 1);
        ::close(child);
        ::unlinkat(folder_fd, entry->d_name, AT_REMOVEDIR);
      }
    }
    if (!found) return;
  }
}

void removeFolderTree(const char* path) noexcept {
  const int folder = ::open(path, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (folder < 0) return;
  removeFolderContents(folder, kTemporaryFolderDepth);
  ::close(folder);
  ::rmdir(path);
}

// SIGINT, SIGTERM, SIGHUP: remove the temporaries, then end by the same signal with its
// default action (so the exit status still says which signal it was).
extern "C" void removeTemporariesAndEnd(int signal) {
  removeLiveTemporaries();
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  sigaction(signal, &action, nullptr);
  ::raise(signal);
}

}  // namespace

void removeLiveTemporaries() noexcept {
  const int saved_errno = errno;
  for (LiveTemporary& temporary : g_live_temporaries) {
    if (!temporary.live.load(std::memory_order_acquire)) continue;
    if (temporary.folder)
      removeFolderTree(temporary.path);
    else
      ::unlink(temporary.path);
  }
  errno = saved_errno;
}

LiveTemporaryFolder::LiveTemporaryFolder(const fs::path& folder) : slot_(claimTemporarySlot(folder, true)) {}

LiveTemporaryFolder::~LiveTemporaryFolder() { releaseTemporarySlot(slot_); }

BlockedTerminationSignals::BlockedTerminationSignals() {
  sigset_t block;
  sigemptyset(&block);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&block, signal);
  pthread_sigmask(SIG_BLOCK, &block, &previous_mask_);
}

BlockedTerminationSignals::~BlockedTerminationSignals() {
  pthread_sigmask(SIG_SETMASK, &previous_mask_, nullptr);
}

void removeTemporariesOnSignals() {
  struct sigaction action {};
  action.sa_handler = removeTemporariesAndEnd;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    sigaction(signal, nullptr, &old);
    if (old.sa_handler == SIG_IGN) continue;  // e.g. SIGHUP under nohup stays ignored
    sigaction(signal, &action, nullptr);
  }
}

void writeAtomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path folder = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder, "cannot create output folder: " + ec.message());
  // Hidden, unique per process and call, same extension so writers pick the same format.
  const fs::path temporary = folder / ("." + target.stem().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                                       std::to_string(counter++) + target.extension().string());
  const TemporaryRegistration registration(temporary);
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
