// One farm per output folder: tessera-up holds an advisory lock on <folder>/.tessera-farm
// for its whole run, so a second farm pointed at the same folder refuses to start instead of
// writing its frames over the first one's and splicing the two metrics.jsonl streams.
#pragma once
#include <filesystem>

namespace tessera::launcher {

// Removes frame_NNNNNN.png and .pam files an earlier run left in `folder` (a shorter run
// would otherwise leave them beside its own, looking like its frames); returns how many.
// Call it holding the folder's lock.
int removeOldFrames(const std::filesystem::path& folder);

class OutputLock {
 public:
  // Creates the folder if needed and takes the lock; throws LaunchError naming the folder
  // and the farm that holds it (its tessera-up pid) if another live farm has it.
  explicit OutputLock(const std::filesystem::path& folder);
  ~OutputLock();  // releases the lock and removes the lock file
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace tessera::launcher
