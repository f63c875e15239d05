#pragma once
// Output files that are never half there and never fail silently. Whole files (summary.json,
// snapshots, indices, checkpoints) are written to a temporary name beside the target and renamed
// over it once complete, so a reader, a crash or kill -9 sees the old file or the new one, never a
// torn one. Growing files (probe CSVs, steering.log) get whole lines: each line is one write(), and
// a line that did not fit (a full disk) is cut off again. Every write, close and rename is checked;
// a failure is an OutputError naming the file and the system's reason (exit 5, docs/cli.md).
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace spate {

struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "<path>: <what>: <strerror(errno)>" as an OutputError.
[[noreturn]] void throw_output_error(const std::filesystem::path& path, const std::string& what, int error_number);

// The temporary name a file is written under before it is renamed into place (same folder, so the
// rename is atomic; the process id keeps two writers apart).
std::filesystem::path temporary_path(const std::filesystem::path& path);
// Whether a file name is one of those temporary names ("NAME.tmp<pid>"), for watchers of a folder
// that must not take a file being written for a finished one.
bool is_temporary_name(const std::string& name);

// Creates the folder (and its parents); OutputError when it cannot.
void create_output_folder(const std::filesystem::path& folder);

// Another process holds the output folder (OutputFolderLock).
struct OutputFolderBusy : OutputError {
  using OutputError::OutputError;
};

// One run's claim on its output folder: an exclusive flock() on the folder itself (no file is
// added to it), held while the object lives and dropped by the kernel when the process ends, even
// by kill -9. Two `spate run`s into one --out would otherwise interleave their probes, snapshots and
// summary.json without a word; the second is refused instead (docs/cli.md).
class OutputFolderLock {
 public:
  // Creates the folder if needed and claims it: OutputFolderBusy when another process holds it,
  // OutputError when it cannot be created or opened.
  explicit OutputFolderLock(const std::filesystem::path& folder);
  ~OutputFolderLock();
  OutputFolderLock(const OutputFolderLock&) = delete;
  OutputFolderLock& operator=(const OutputFolderLock&) = delete;
  // Whether another process holds the folder now (false for a folder that does not exist).
  static bool held_elsewhere(const std::filesystem::path& folder);

 private:
  int fd_ = -1;
};

// A whole file written in pieces, published by commit() (tmp + rename). Dropped without commit()
// (an exception on the way), the temporary file is removed.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  void write(std::string_view bytes);
  void write(const void* data, std::size_t size) { write(std::string_view(static_cast<const char*>(data), size)); }
  void commit();
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_, tmp_;
  int fd_ = -1;
};

void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// Rename of a finished temporary file into place (for writers that make their own temporary file,
// like HDF5's); OutputError when it fails.
void publish_file(const std::filesystem::path& tmp, const std::filesystem::path& path);

// A file that grows by whole lines (O_APPEND; one write() per line).
class AppendFile {
 public:
  AppendFile() = default;
  explicit AppendFile(std::filesystem::path path, bool truncate);
  ~AppendFile();
  AppendFile(AppendFile&& other) noexcept;
  AppendFile& operator=(AppendFile&& other) noexcept;
  bool is_open() const { return fd_ >= 0; }
  // Appends `line` (which should end in '\n'); on failure the file is cut back to its length before.
  void append(std::string_view line);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace spate
