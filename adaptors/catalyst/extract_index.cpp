#include "extract_index.hpp"

#include "io/output_file.hpp"

#include <fcntl.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <tuple>

namespace spate::catalyst {

namespace {

constexpr std::uint32_t kEvents = IN_CLOSE_WRITE | IN_MOVED_TO | IN_CREATE;

// CSV field: quoted when it holds a comma, quote or line break.
std::string csv(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

ExtractIndex::ExtractIndex(std::filesystem::path out_dir) : out_(std::move(out_dir)) {
  fd_ = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (fd_ < 0) return;  // no index then (written empty at the end)
  watch(out_);
  std::error_code ec;
  // Folders of an earlier run in the same output folder (insitu/ above all) are written again.
  for (auto& e : std::filesystem::directory_iterator(out_, ec))
    if (e.is_directory(ec)) watch(e.path());
}

ExtractIndex::~ExtractIndex() {
  if (fd_ >= 0) close(fd_);
}

void ExtractIndex::watch(const std::filesystem::path& dir) {
  if (fd_ < 0) return;
  const int wd = inotify_add_watch(fd_, dir.c_str(), kEvents | IN_ONLYDIR);
  if (wd >= 0) watched_[wd] = dir;
}

std::vector<std::string> ExtractIndex::drain(bool keep_new_folders) {
  std::vector<std::string> written;
  if (fd_ < 0) return written;
  alignas(inotify_event) char buffer[64 * 1024];
  for (;;) {
    const ssize_t n = read(fd_, buffer, sizeof buffer);
    if (n <= 0) break;
    for (ssize_t at = 0; at < n;) {
      const auto* e = reinterpret_cast<const inotify_event*>(buffer + at);
      at += static_cast<ssize_t>(sizeof(inotify_event) + e->len);
      const auto dir = watched_.find(e->wd);
      if (dir == watched_.end() || e->len == 0) continue;
      const std::filesystem::path path = dir->second / e->name;
      if (e->mask & IN_ISDIR) {
        // A folder a pipeline makes (its extracts folder): watch it, and take what is already in
        // it (written before the watch existed).
        if (keep_new_folders && (e->mask & IN_CREATE)) {
          watch(path);
          std::error_code ec;
          for (auto& f : std::filesystem::recursive_directory_iterator(path, ec)) {
            if (f.is_directory(ec)) watch(f.path());
            else written.push_back(f.path().lexically_relative(out_).string());
          }
        }
        continue;
      }
      if (!(e->mask & (IN_CLOSE_WRITE | IN_MOVED_TO))) continue;
      const std::string name = e->name;
      if (path == this->path() || is_temporary_name(name) || name.find(".tmp.") != std::string::npos) continue;
      written.push_back(path.lexically_relative(out_).string());
    }
  }
  return written;
}

void ExtractIndex::begin_step() { drain(false); }

void ExtractIndex::record(std::int64_t step, double time, const std::string& pipeline) {
  for (auto& file : drain(true)) {
    files_[file] = Entry{step, time, pipeline};
    dirty_ = true;
  }
}

std::string ExtractIndex::write(bool force) {
  const auto now = std::chrono::steady_clock::now();
  if (!dirty_ || (!force && now - written_ < std::chrono::seconds(1))) return {};
  std::vector<std::tuple<std::int64_t, std::string, std::string, double>> rows;
  for (auto& [file, e] : files_) rows.emplace_back(e.step, e.pipeline, file, e.time);
  std::sort(rows.begin(), rows.end());
  std::string text = "step,time[s],pipeline,file\n";
  for (auto& [step, pipeline, file, time] : rows) text += fmt::format("{},{:.10g},{},{}\n", step, time, csv(pipeline), csv(file));
  const auto target = path();
  try {
    create_output_folder(target.parent_path());
    write_file_atomically(target, text);
  } catch (const OutputError& e) {
    return fmt::format("cannot write the in-situ index: {}", e.what());
  }
  written_ = now;
  dirty_ = false;
  drain(false);  // our own rename
  return {};
}

}  // namespace spate::catalyst
