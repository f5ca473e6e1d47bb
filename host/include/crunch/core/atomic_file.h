// Writing a file atomically: the content goes into a fresh temporary file beside the target,
// which is synced and renamed over the target, so a reader sees either the old file (or none)
// or the complete new one, never half a file. The one implementation behind map.json,
// report.json, models files, map pictures and charts.
#pragma once

#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "crunch/core/result.h"

namespace crunch {

// A temporary file beside `target`, renamed over it by commit(); removed by the destructor
// when not committed, so no failure path leaves a temporary behind or touches the target.
//
// The temporary is "<target>.tmp.<pid>.XXXXXX" made by mkstemp, so several writers aiming at the
// same target (threads or processes) never share one; the last commit wins, whole. Its mode is
// 0644 (best effort: some file systems refuse chmod, and the content is what matters). The pid
// in the name lets a later run remove what a killed one left (removeStaleTemps), and every
// temporary alive in the process is removed by a SIGINT/SIGTERM/SIGHUP once
// removeTempsOnSignals() is installed.
//
// Write the content either with write() or, for a library that wants a file name (Cairo), to
// tempPath(): truncating and rewriting that file is fine, the object's own descriptor stays on
// the same file and commit() syncs it.
//
// Every failure is an Error naming the target and the system's reason. By default it reads
// "<target>: cannot write file: <step>: <reason>"; a caller with its own wording passes
// `message`, which gets the target and "<step>: <reason>".
class AtomicFile {
 public:
  using ErrorMessage = Error (*)(const std::string& target, const std::string& why);

  // Creates the temporary file. Fails when the target's directory is missing or unwritable.
  static Result<AtomicFile> create(const std::string& target, ErrorMessage message = nullptr);

  ~AtomicFile();
  AtomicFile(AtomicFile&& other) noexcept;
  AtomicFile& operator=(AtomicFile&& other) noexcept;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& target() const { return target_; }
  // Where to write the content; valid until commit() or destruction.
  const std::string& tempPath() const { return temp_; }

  // Appends `bytes` to the temporary file (all of them, retrying short writes).
  Status write(std::string_view bytes);

  // fsyncs and closes the temporary, renames it over the target, then fsyncs the directory
  // (best effort: the new file is already in place, and some file systems refuse). On failure
  // the temporary is removed and the target is untouched. Call at most once. The same as
  // seal() then publish().
  Status commit();

  // commit()'s two halves, for OutputSet: seal() makes the temporary complete and durable
  // (fsync, close; no more write()); publish() renames a sealed temporary over the target.
  Status seal();
  Status publish();

 private:
  AtomicFile(std::string target, std::string temp, int fd, ErrorMessage message);
  // The Error for `step`, with errno's reason.
  Error failure(const std::string& step, int err) const;
  void discard();

  std::string target_;
  std::string temp_;  // empty once committed or discarded
  int fd_ = -1;       // -1 once sealed
  ErrorMessage message_ = nullptr;
  int live_slot_ = -1;  // the temporary's entry for the signal handler, -1 if none
};

// All-or-nothing outputs (issue 16): a run's files are each written to an AtomicFile's
// temporary first, and publish() renames them over their targets only once every one of them
// is complete and synced. An error before that, the OutputSet's destruction, or a signal (with
// removeTempsOnSignals) leaves no output and no temporary, and any old outputs untouched. The
// renames themselves take microseconds; a kill -9 inside them is the one way to see some files
// new and some old.
class OutputSet {
 public:
  // A new AtomicFile for `path` to write into (write() or tempPath()), owned by the set.
  Result<AtomicFile*> add(const std::string& path, AtomicFile::ErrorMessage message = nullptr);
  // add(path) with `contents` written: writeFileAtomic's staged twin.
  Status stage(const std::string& path, std::string_view contents);
  // Seals every file, then renames each over its target. On a failure while sealing nothing is
  // published and every temporary is removed. Call at most once.
  Status publish();
  size_t size() const { return files_.size(); }

 private:
  std::vector<std::unique_ptr<AtomicFile>> files_;
};

// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove every AtomicFile temporary alive
// in the process, then die of the signal as before (the default action, re-raised). A handler
// installed later over it (crunchhost --robot's StopSignals) takes precedence while it lives.
// Async-signal-safe: the handler only reads a fixed table and calls unlink().
void removeTempsOnSignals();

// Removes "<dir>/<name>.tmp.<pid>.*" left by a process that no longer runs (a kill -9, a power
// cut), for each of `names`; a live process's temporaries are left alone. Returns how many were
// removed. Best effort: what cannot be removed is left.
int removeStaleTemps(const std::string& dir, std::initializer_list<const char*> names);

// Writes `contents` to `path` through an AtomicFile. On failure `path` is untouched (old
// content or absent), no temporary is left, and the Error reads
// "<path>: cannot write file: <step>: <reason>".
Status writeFileAtomic(const std::string& path, std::string_view contents);

// Creates `dir` and any missing parents; succeeds if it already is a directory. The Error names
// the directory.
Status ensureDirectory(const std::string& dir);

// Whether a run can write `names` into `dir`, checked before the run starts so that a bad --out
// costs nothing (issue 16): `dir` is absent (it will be created: its nearest existing ancestor
// must be a writable directory) or a writable directory, and no `dir/name` is a directory. Creates
// nothing. The Error names the path: "<path>: cannot write output: <why>".
Status checkOutputTargets(const std::string& dir, std::initializer_list<const char*> names);

}  // namespace crunch
