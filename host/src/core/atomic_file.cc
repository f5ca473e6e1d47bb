#include "crunch/core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cassert>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <utility>

namespace crunch {

namespace {

Error defaultMessage(const std::string& target, const std::string& why) {
  return Error{target + ": cannot write file: " + why};
}

// The temporaries alive in the process, for the signal handler: a fixed table (no allocation in
// the handler). A slot is free (0), being filled or emptied (1), or holds a path (2).
constexpr int kLiveSlots = 64;
struct LiveTemp {
  std::atomic<int> state{0};
  char path[4096];
};
LiveTemp g_live[kLiveSlots];

// A slot now naming `temp`, or -1 when the table is full or the path too long (that temporary
// is then only removed by its AtomicFile or by a later removeStaleTemps).
int trackTemp(const std::string& temp) {
  if (temp.size() >= sizeof g_live[0].path) return -1;
  for (int i = 0; i < kLiveSlots; ++i) {
    int free_state = 0;
    if (g_live[i].state.compare_exchange_strong(free_state, 1)) {
      std::memcpy(g_live[i].path, temp.c_str(), temp.size() + 1);
      g_live[i].state.store(2);
      return i;
    }
  }
  return -1;
}

void untrackTemp(int& slot) {
  if (slot >= 0) g_live[slot].state.store(0);
  slot = -1;
}

extern "C" void removeTempsAndDie(int sig) {
  const int saved = errno;
  for (LiveTemp& t : g_live) {
    if (t.state.load() == 2) ::unlink(t.path);
  }
  errno = saved;
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

void removeTempsOnSignals() {
  struct sigaction sa {};
  sa.sa_handler = removeTempsAndDie;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&sa.sa_mask, sig);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
}

int removeStaleTemps(const std::string& dir, std::initializer_list<const char*> names) {
  namespace fs = std::filesystem;
  std::error_code ec;
  int removed = 0;
  fs::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::string file = it->path().filename().string();
    for (const char* name : names) {
      // "<name>.tmp.<pid>.XXXXXX"
      const std::string prefix = std::string(name) + ".tmp.";
      if (file.compare(0, prefix.size(), prefix) != 0) continue;
      const char* digits = file.c_str() + prefix.size();
      char* after = nullptr;
      errno = 0;
      const long pid = std::strtol(digits, &after, 10);
      if (after == digits || *after != '.' || std::strlen(after) != 7 || errno != 0 || pid <= 0 ||
          pid == ::getpid()) {
        continue;
      }
      // ESRCH: no such process. EPERM means it runs (as someone else): leave it.
      if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH &&
          ::unlink(it->path().c_str()) == 0) {
        ++removed;
      }
    }
  }
  return removed;
}

Result<AtomicFile> AtomicFile::create(const std::string& target, ErrorMessage message) {
  if (message == nullptr) message = defaultMessage;
  std::string temp = target + ".tmp." + std::to_string(::getpid());
  temp += ".XXXXXX";
  const int fd = ::mkostemp(temp.data(), O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return message(target,
                   std::string("creating a temporary file beside it: ") + std::strerror(err));
  }
  ::fchmod(fd, 0644);  // mkstemp makes 0600; an output file is for everyone to read
  return AtomicFile(target, std::move(temp), fd, message);
}

AtomicFile::AtomicFile(std::string target, std::string temp, int fd, ErrorMessage message)
    : target_(std::move(target)), temp_(std::move(temp)), fd_(fd), message_(message) {
  live_slot_ = trackTemp(temp_);
}

AtomicFile::~AtomicFile() { discard(); }

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : target_(std::move(other.target_)),
      temp_(std::exchange(other.temp_, std::string())),
      fd_(std::exchange(other.fd_, -1)),
      message_(other.message_),
      live_slot_(std::exchange(other.live_slot_, -1)) {}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    discard();
    target_ = std::move(other.target_);
    temp_ = std::exchange(other.temp_, std::string());
    fd_ = std::exchange(other.fd_, -1);
    message_ = other.message_;
    live_slot_ = std::exchange(other.live_slot_, -1);
  }
  return *this;
}

void AtomicFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
  untrackTemp(live_slot_);
}

Error AtomicFile::failure(const std::string& step, int err) const {
  return message_(target_, step + ": " + std::strerror(err));
}

Status AtomicFile::write(std::string_view bytes) {
  assert(fd_ >= 0 && "AtomicFile::write after commit()");
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
    if (n < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      return failure("writing '" + temp_ + "'", err);
    }
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  return okStatus();
}

Status AtomicFile::commit() {
  if (Status s = seal(); !s) return s;
  return publish();
}

Status AtomicFile::seal() {
  assert(fd_ >= 0 && "AtomicFile::seal after seal() or commit()");
  // Reads errno before building strings or discard() (close, unlink) can change it.
  auto fail = [&](const char* verb) -> Status {
    const int err = errno;
    const Error e = failure(std::string(verb) + " '" + temp_ + "'", err);
    discard();
    return e;
  };
  if (::fsync(fd_) != 0) return fail("syncing");
  // Closing may be where a failed write first shows (NFS, quotas).
  if (::close(std::exchange(fd_, -1)) != 0) return fail("closing");
  return okStatus();
}

Status AtomicFile::publish() {
  assert(fd_ < 0 && !temp_.empty() && "AtomicFile::publish needs a sealed temporary");
  if (::rename(temp_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    const Error e = failure("renaming '" + temp_ + "' over it", err);
    discard();
    return e;
  }
  temp_.clear();
  untrackTemp(live_slot_);

  // Make the rename itself durable. Best effort only: the new file is already in place.
  const std::filesystem::path parent = std::filesystem::path(target_).parent_path();
  const std::string dir = parent.empty() ? std::string(".") : parent.string();
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return okStatus();
}

Result<AtomicFile*> OutputSet::add(const std::string& path, AtomicFile::ErrorMessage message) {
  Result<AtomicFile> file = AtomicFile::create(path, message);
  if (!file) return file.error();
  files_.push_back(std::make_unique<AtomicFile>(std::move(file).value()));
  return files_.back().get();
}

Status OutputSet::stage(const std::string& path, std::string_view contents) {
  Result<AtomicFile*> file = add(path);
  if (!file) return file.error();
  return file.value()->write(contents);
}

Status OutputSet::publish() {
  for (auto& f : files_) {
    if (Status s = f->seal(); !s) {
      files_.clear();  // removes every temporary
      return s;
    }
  }
  Status first = okStatus();
  for (auto& f : files_) {
    // A rename in the same directory fails only if the target changed under us (say, became a
    // directory); the others are still published and the first failure is reported.
    if (Status s = f->publish(); !s && first) first = s;
  }
  files_.clear();
  return first;
}

Status writeFileAtomic(const std::string& path, std::string_view contents) {
  Result<AtomicFile> file = AtomicFile::create(path);
  if (!file) return file.error();
  if (Status s = file.value().write(contents); !s) return s;
  return file.value().commit();
}

Status checkOutputTargets(const std::string& dir, std::initializer_list<const char*> names) {
  if (dir.empty()) return Error{"output directory: the name is empty"};
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path d(dir);
  if (fs::exists(d, ec)) {
    if (!fs::is_directory(d, ec)) {
      return Error{dir + ": cannot write output: exists and is not a directory"};
    }
    if (::access(dir.c_str(), W_OK | X_OK) != 0) {
      return Error{dir + ": cannot write output: " + std::strerror(errno)};
    }
    for (const char* name : names) {
      const fs::path target = d / name;
      if (fs::is_directory(target, ec)) {
        return Error{target.string() + ": cannot write output: is a directory"};
      }
    }
    return okStatus();
  }
  // Absent: the nearest existing ancestor must be a directory we may create entries in.
  fs::path up = fs::absolute(d, ec).parent_path();
  while (!up.empty() && !fs::exists(up, ec) && up != up.root_path()) up = up.parent_path();
  if (!fs::is_directory(up, ec)) {
    return Error{dir + ": cannot write output: " + up.string() + " is not a directory"};
  }
  if (::access(up.c_str(), W_OK | X_OK) != 0) {
    return Error{dir + ": cannot write output: cannot create it in " + up.string() + ": " +
                 std::strerror(errno)};
  }
  return okStatus();
}

Status ensureDirectory(const std::string& dir) {
  if (dir.empty()) return Error{"output directory: the name is empty"};
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Error{dir + ": cannot create directory: " + ec.message()};
  if (!std::filesystem::is_directory(dir, ec)) {
    return Error{dir + ": cannot create directory: exists and is not a directory"};
  }
  return okStatus();
}

}  // namespace crunch
