#pragma once
// Writing outputs without ever leaving a half-written file behind.

#include <csignal>
#include <filesystem>
#include <functional>
#include <string>

namespace solo {

/// Calls write(temporary_path) with a temporary path in the folder of `target` that
/// keeps the target's extension (so format-by-extension writers still work), then
/// renames it onto `target`. If write throws, the temporary file is removed and the
/// exception propagates (an InputError naming the temporary is renamed to name `target`);
/// `target` is then untouched. Creates missing parent folders. `write` must check its writes
/// and its final close: what it returns from is moved into place.
void writeAtomically(const std::filesystem::path& target,
                     const std::function<void(const std::filesystem::path& temporary)>& write);

/// Writes `text` to `target` atomically.
void writeTextAtomically(const std::filesystem::path& target, const std::string& text);

/// Removes every hidden temporary writeAtomically is writing at this moment and every live
/// LiveTemporaryFolder. Async-signal-safe (unlink, open, getdents64, unlinkat and close only): for
/// signal handlers.
void removeLiveTemporaries() noexcept;

/// While it lives, the hidden folder `folder` and everything in it (four levels deep) are
/// removed by removeLiveTemporaries, hence by the handlers of removeTemporariesOnSignals: for an
/// output written into a staging folder that is renamed into place at the end.
class LiveTemporaryFolder {
 public:
  explicit LiveTemporaryFolder(const std::filesystem::path& folder);
  ~LiveTemporaryFolder();
  LiveTemporaryFolder(const LiveTemporaryFolder&) = delete;
  LiveTemporaryFolder& operator=(const LiveTemporaryFolder&) = delete;

 private:
  int slot_ = -1;
};

/// While it lives, SIGINT, SIGTERM and SIGHUP wait (blocked for the calling thread): for the
/// few renames that swap a finished output into place, which a signal must not split.
class BlockedTerminationSignals {
 public:
  BlockedTerminationSignals();
  ~BlockedTerminationSignals();
  BlockedTerminationSignals(const BlockedTerminationSignals&) = delete;
  BlockedTerminationSignals& operator=(const BlockedTerminationSignals&) = delete;

 private:
  sigset_t previous_mask_;
};

/// Installs handlers for SIGINT, SIGTERM and SIGHUP (those not ignored) that remove the live
/// temporaries, then end the process by the same signal with its default action, so the exit
/// status still says which signal it was. A handler installed later (the batch's) takes over
/// until it restores this one.
void removeTemporariesOnSignals();

}  // namespace solo
