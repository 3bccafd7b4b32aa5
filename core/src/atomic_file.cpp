#include "solo/core/atomic_file.h"

#include "solo/core/error.h"

#include <atomic>
#include <csignal>
#include <cstring>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace solo {
namespace {

// The hidden temporaries being written right now, as plain C strings a signal handler can
// unlink without allocating. A slot is claimed, filled, then marked live; the handler only
// reads live slots.
constexpr int kTemporarySlots = 64;
constexpr std::size_t kTemporaryPathBytes = 4096;

struct LiveTemporary {
  std::atomic<bool> claimed{false};
  std::atomic<bool> live{false};
  char path[kTemporaryPathBytes] = {};
};

LiveTemporary g_live_temporaries[kTemporarySlots];

// Registers a temporary with the signal handler for as long as it exists. More than
// kTemporarySlots at once (never in solo) or a longer path go unregistered.
class TemporaryRegistration {
 public:
  explicit TemporaryRegistration(const fs::path& temporary) {
    std::error_code ec;
    const std::string text = fs::absolute(temporary, ec).string();
    if (ec || text.size() >= kTemporaryPathBytes) return;
    for (int i = 0; i < kTemporarySlots; ++i) {
      bool expected = false;
      if (!g_live_temporaries[i].claimed.compare_exchange_strong(expected, true)) continue;
      std::memcpy(g_live_temporaries[i].path, text.c_str(), text.size() + 1);
      g_live_temporaries[i].live.store(true, std::memory_order_release);
      slot_ = i;
      return;
    }
  }
  ~TemporaryRegistration() {
    if (slot_ < 0) return;
    g_live_temporaries[slot_].live.store(false, std::memory_order_release);
    g_live_temporaries[slot_].claimed.store(false, std::memory_order_release);
  }
  TemporaryRegistration(const TemporaryRegistration&) = delete;
  TemporaryRegistration& operator=(const TemporaryRegistration&) = delete;

 private:
  int slot_ = -1;
};

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
  for (LiveTemporary& temporary : g_live_temporaries)
    if (temporary.live.load(std::memory_order_acquire)) ::unlink(temporary.path);
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
