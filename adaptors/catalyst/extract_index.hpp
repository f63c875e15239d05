#pragma once
// The in-situ index: every file the pipelines write during in-situ steps (images, data extracts),
// with the step, the simulated time and the pipeline that wrote it, in <out>/insitu/index.csv:
//
//   step,time[s],pipeline,file
//   0,0,pipelines/free_surface.py,insitu/free_surface_000000.png
//
// (file relative to the run's output folder). The files are seen through inotify: while an in-situ
// step runs the solver writes nothing, so whatever is closed after writing in the output folder
// (and in folders the pipelines create) then is a pipeline's; it belongs to the script that was
// running. A file rewritten later is listed once, at its last step. The index is rewritten whole
// (temporary file + rename, so a reader never sees half of it), at most once a second while the
// run goes on and at the end. Files of a script that crashed or hung in that step are not listed.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace spate::catalyst {

class ExtractIndex {
 public:
  explicit ExtractIndex(std::filesystem::path out_dir);
  ~ExtractIndex();
  ExtractIndex(const ExtractIndex&) = delete;
  ExtractIndex& operator=(const ExtractIndex&) = delete;

  // Forgets what was written since the last call (the solver's own outputs between in-situ steps).
  void begin_step();
  // The files written since the last call belong to `pipeline` at this step.
  void record(std::int64_t step, double time, const std::string& pipeline);
  // Drops what was written since the last call (a script that crashed or hung).
  void discard() { begin_step(); }
  // Rewrites index.csv if something changed (force: now; else at most once a second). Returns an
  // error text, empty on success.
  std::string write(bool force);
  std::filesystem::path path() const { return out_ / "insitu" / "index.csv"; }

 private:
  struct Entry {
    std::int64_t step;
    double time;
    std::string pipeline;
  };
  std::vector<std::string> drain(bool keep_new_folders);
  void watch(const std::filesystem::path& dir);

  std::filesystem::path out_;
  int fd_ = -1;
  std::map<int, std::filesystem::path> watched_;  // watch descriptor -> folder
  std::map<std::string, Entry> files_;            // file (relative to out_) -> its last writer
  bool dirty_ = false;
  std::chrono::steady_clock::time_point written_{};
};

}  // namespace spate::catalyst
