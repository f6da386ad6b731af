#pragma once
// Files written whole or not at all, and read with a bound on their size.
//
// Every file pidlab writes goes to a temporary file in the target's own
// folder, is flushed and synced, and is then renamed into place, so a reader
// sees the old file or the new one, never a part. A failure (a full disk, a
// folder that cannot be written, a directory where the file should be)
// leaves the old files untouched, removes the temporaries, and returns a
// Status whose message names the path and the system's own words for the
// cause ("No space left on device"). kIoFailed is a runtime failure (exit 1);
// a target that is a directory or a read-only file is kInvalidInput (exit 2:
// an output path that cannot be written is something the user gave).

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pidlab/spec/status.h"

namespace pidlab::io {

/// Ok unless `path` cannot take a new file: it is a directory, a read-only
/// file (no write bit, which root would otherwise ignore), or its folder is
/// missing. Checks only; writes nothing.
Status CheckWritableTarget(const std::string& path);

/// One file written whole or not at all. Bytes go to a temporary file beside
/// `path`; Commit() flushes, syncs and renames it into place. Until Commit()
/// succeeds `path` is untouched; destroying an uncommitted file removes its
/// temporary. The first failure is kept: later Write()s do nothing and
/// Commit() returns it.
class AtomicFile {
 public:
  /// Creates the temporary for `path` (CheckWritableTarget first).
  static Status Open(const std::string& path, std::unique_ptr<AtomicFile>* out);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends `bytes` (buffered).
  void Write(std::string_view bytes);
  /// Ok until a write has failed.
  const Status& status() const { return status_; }
  /// Flushes, syncs, closes and renames into place (the folder synced too).
  Status Commit();
  /// Flushes, syncs and closes, but keeps the temporary: Publish() renames it.
  /// Several files prepared first and published together fail or succeed as
  /// a group far more often than one by one (WriteFiles).
  Status Prepare();
  /// Renames a prepared temporary into place.
  Status Publish();
  const std::string& path() const { return path_; }
  const std::string& temporary_path() const { return temp_path_; }

 private:
  AtomicFile(std::string path, std::string temp_path, int fd);
  void Flush();
  void Fail(const std::string& what, int error_number);
  void Discard();

  std::string path_, temp_path_;
  int fd_ = -1;
  std::string buffer_;
  Status status_;
  bool prepared_ = false, published_ = false;
};

/// `bytes` into `path`, whole or not at all.
Status WriteFile(const std::string& path, std::string_view bytes);

/// Every (path, bytes) written, or none: each is written and synced to its
/// temporary first; only when all are complete are they renamed into place
/// (should a rename still fail, the files renamed before it get their old
/// content back).
Status WriteFiles(const std::vector<std::pair<std::string, std::string>>& files);

/// A folder's new content, written into a staging folder inside it
/// (DIR/.pidlab-staging-XXXXXX) and moved into DIR by Commit(): a writer that
/// makes many files (a report, a figure and its data) writes into path() and
/// either all of its files land or none does. Destroying an uncommitted
/// stage removes it and everything in it.
class StagedFolder {
 public:
  /// Creates DIR (and its parents) if needed, then the staging folder.
  static Status Create(const std::string& dir, std::unique_ptr<StagedFolder>* out);
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;
  /// Where the writer writes.
  const std::string& path() const { return stage_; }
  /// `message` with the stage's path (as given or absolute) replaced by the
  /// folder's: a writer's error names the file the user asked for.
  std::string Unstaged(std::string message) const;
  /// Syncs every staged file, then renames each into DIR (subfolders merged
  /// into DIR's own), replacing files of the same name; removes the stage.
  Status Commit();

 private:
  StagedFolder(std::string dir, std::string stage) : dir_(std::move(dir)), stage_(std::move(stage)) {}
  std::string dir_, stage_;
  bool committed_ = false;
};

/// `path` opened for reading into *fd (the caller closes it), refused before
/// anything is read when it is not a regular file: a FIFO, a device or a
/// folder is kInvalidInput ("'F' is not a regular file") at once, never a
/// wait for a writer. Every reader of a file a user names opens it here.
Status OpenRegularFile(const std::string& path, int* fd);

/// The whole of `path`, at most `max_bytes` (kInvalidInput beyond, and for a
/// file that cannot be opened or is not a regular file, naming the errno's
/// words).
Status ReadFile(const std::string& path, std::size_t max_bytes, std::string* text);

}  // namespace pidlab::io
