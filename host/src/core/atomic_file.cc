#include "crunch/core/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

}  // namespace

Result<AtomicFile> AtomicFile::create(const std::string& target, ErrorMessage message) {
  if (message == nullptr) message = defaultMessage;
  std::string temp = target + ".tmp.XXXXXX";
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
    : target_(std::move(target)), temp_(std::move(temp)), fd_(fd), message_(message) {}

AtomicFile::~AtomicFile() { discard(); }

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : target_(std::move(other.target_)),
      temp_(std::exchange(other.temp_, std::string())),
      fd_(std::exchange(other.fd_, -1)),
      message_(other.message_) {}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    discard();
    target_ = std::move(other.target_);
    temp_ = std::exchange(other.temp_, std::string());
    fd_ = std::exchange(other.fd_, -1);
    message_ = other.message_;
  }
  return *this;
}

void AtomicFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
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
  assert(fd_ >= 0 && "AtomicFile::commit called twice");
  // Reads errno before building strings or discard() (close, unlink) can change it.
  auto fail = [&](const char* verb, const char* rest = "") -> Status {
    const int err = errno;
    const Error e = failure(std::string(verb) + " '" + temp_ + "'" + rest, err);
    discard();
    return e;
  };
  if (::fsync(fd_) != 0) return fail("syncing");
  // Closing may be where a failed write first shows (NFS, quotas).
  if (::close(std::exchange(fd_, -1)) != 0) return fail("closing");
  if (::rename(temp_.c_str(), target_.c_str()) != 0) return fail("renaming", " over it");
  temp_.clear();

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
