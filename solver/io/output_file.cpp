#include "output_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>
#include <utility>

namespace spate {

void throw_output_error(const std::filesystem::path& path, const std::string& what, int error_number) {
  throw OutputError(path.string() + ": " + what + ": " + std::strerror(error_number));
}

std::filesystem::path temporary_path(const std::filesystem::path& path) {
  return path.string() + ".tmp" + std::to_string(::getpid());
}

bool is_temporary_name(const std::string& name) {
  const auto at = name.rfind(".tmp");
  if (at == std::string::npos) return false;
  const auto digits = name.substr(at + 4);
  return std::all_of(digits.begin(), digits.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
}

void create_output_folder(const std::filesystem::path& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw OutputError(folder.string() + ": cannot create the folder: " + ec.message());
  if (!std::filesystem::is_directory(folder, ec)) throw OutputError(folder.string() + ": cannot create the folder: not a folder");
}

namespace {

// The folder opened for flock(): -1 with errno set when it cannot be.
int open_folder(const std::filesystem::path& folder) { return ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); }

}  // namespace

OutputFolderLock::OutputFolderLock(const std::filesystem::path& folder) {
  create_output_folder(folder);
  fd_ = open_folder(folder);
  if (fd_ < 0) throw_output_error(folder, "cannot open the folder", errno);
  int rc;
  while ((rc = ::flock(fd_, LOCK_EX | LOCK_NB)) != 0 && errno == EINTR) {
  }
  if (rc == 0) return;
  const int e = errno;
  ::close(fd_);
  fd_ = -1;
  if (e == EWOULDBLOCK) throw OutputFolderBusy(folder.string() + ": another spate run is writing into this folder");
  throw_output_error(folder, "cannot lock the folder", e);
}

OutputFolderLock::~OutputFolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the lock
}

bool OutputFolderLock::held_elsewhere(const std::filesystem::path& folder) {
  const int fd = open_folder(folder);
  if (fd < 0) return false;
  const bool busy = ::flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  return busy;
}

namespace {

// write() until done; false (errno set) on failure. EINTR is retried.
bool write_all(int fd, const char* data, std::size_t size, std::size_t* written = nullptr) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      if (written) *written = done;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  if (written) *written = done;
  return true;
}

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)), tmp_(temporary_path(path_)) {
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw_output_error(tmp_, "cannot create", errno);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(tmp_.c_str());
  }
}

void AtomicFile::write(std::string_view bytes) {
  if (fd_ < 0) throw OutputError(path_.string() + ": write after commit");
  if (!write_all(fd_, bytes.data(), bytes.size())) throw_output_error(tmp_, "cannot write", errno);
}

void AtomicFile::commit() {
  const int fd = std::exchange(fd_, -1);
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp_.c_str());
    throw_output_error(tmp_, "cannot write (on close)", e);
  }
  publish_file(tmp_, path_);
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile f(path);
  f.write(content);
  f.commit();
}

void publish_file(const std::filesystem::path& tmp, const std::filesystem::path& path) {
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw_output_error(path, "cannot rename the finished file into place", e);
  }
}

AppendFile::AppendFile(std::filesystem::path path, bool truncate) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | (truncate ? O_TRUNC : 0), 0644);
  if (fd_ < 0) throw_output_error(path_, "cannot open for writing", errno);
}

AppendFile::~AppendFile() {
  if (fd_ >= 0) ::close(fd_);
}

AppendFile::AppendFile(AppendFile&& other) noexcept : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)) {}

AppendFile& AppendFile::operator=(AppendFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

void AppendFile::append(std::string_view line) {
  if (fd_ < 0) throw OutputError(path_.string() + ": not open");
  struct stat st{};
  const bool sized = ::fstat(fd_, &st) == 0;
  std::size_t written = 0;
  if (write_all(fd_, line.data(), line.size(), &written)) return;
  const int e = errno;
  // Half a line would be read as a (wrong) row: cut it off again.
  if (sized && written > 0 && ::ftruncate(fd_, st.st_size) != 0) (void)0;
  throw_output_error(path_, "cannot write", e);
}

}  // namespace spate
