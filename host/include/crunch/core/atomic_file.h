// Writing a file atomically: the content goes into a fresh temporary file beside the target,
// which is synced and renamed over the target, so a reader sees either the old file (or none)
// or the complete new one, never half a file. The one implementation behind map.json,
// report.json, models files, map pictures and charts.
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>

#include "crunch/core/result.h"

namespace crunch {

// A temporary file beside `target`, renamed over it by commit(); removed by the destructor
// when not committed, so no failure path leaves a temporary behind or touches the target.
//
// The temporary is "<target>.tmp.XXXXXX" made by mkstemp, so several writers aiming at the same
// target (threads or processes) never share one; the last commit wins, whole. Its mode is 0644
// (best effort: some file systems refuse chmod, and the content is what matters).
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
  // the temporary is removed and the target is untouched. Call at most once.
  Status commit();

 private:
  AtomicFile(std::string target, std::string temp, int fd, ErrorMessage message);
  // The Error for `step`, with errno's reason.
  Error failure(const std::string& step, int err) const;
  void discard();

  std::string target_;
  std::string temp_;  // empty once committed or discarded
  int fd_ = -1;
  ErrorMessage message_ = nullptr;
};

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
