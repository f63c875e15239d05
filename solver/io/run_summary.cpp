#include "run_summary.hpp"

#include <sys/resource.h>

#include <nlohmann/json.hpp>

#include "output_file.hpp"
#include "provenance.hpp"
#include "version.hpp"

namespace spate {

std::int64_t peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<std::int64_t>(u.ru_maxrss) * 1024;
}

namespace {

// The case and the provenance: which program, from which sources, with which input, where and when.
nlohmann::ordered_json summary_head(const std::string& case_name, const std::string& case_file) {
  nlohmann::ordered_json j;
  j["case"] = case_name;
  j["case_file"] = case_file;
  const Provenance& run = invocation();
  j["version"] = version();
  j["commit"] = git_commit();
  j["command_line"] = run.command_line;
  // Only a regular file is hashed: a refused "case file" may be /dev/zero or a FIFO.
  std::error_code ec;
  j["case_file_sha256"] = std::filesystem::is_regular_file(case_file, ec) ? sha256_of_file(case_file) : std::string();
  j["host"] = run.host;
  j["start_time"] = run.start_time;
  j["end_time"] = utc_timestamp();
  return j;
}

void write_json(const std::filesystem::path& path, const nlohmann::ordered_json& j) {
  if (path.has_parent_path()) create_output_folder(path.parent_path());
  write_file_atomically(path, j.dump(2) + "\n");
}

}  // namespace

void write_summary(const std::filesystem::path& path, const Case& c, const PhysicsParams& P, const RunResult& r,
                   const SummaryExtras& x) {
  nlohmann::ordered_json j = summary_head(c.name, c.file);
  j["warnings"] = x.warnings;
  j["dimensions"] = c.dim;
  j["particles"] = {{"fluid", r.particles.fluid}, {"wall", r.particles.wall}, {"total", r.particles.total()}};
  j["steps"] = r.steps;
  j["final_step"] = r.final_step;
  j["simulated_time"] = r.simulated_time;
  j["wall_seconds"] = r.wall_seconds;
  j["particle_steps_per_second"] = r.wall_seconds > 0 ? static_cast<double>(r.steps) * r.particles.total() / r.wall_seconds : 0.0;
  j["peak_rss_bytes"] = peak_rss_bytes();
  j["bytes_per_particle"] = r.bytes_per_particle;
  j["threads"] = x.threads;
  j["devices"] = x.devices;
  j["ranks"] = x.ranks;
  j["backend"] = x.backend;
  j["dp"] = c.dp;
  j["smoothing_length"] = P.h;
  j["sound_speed"] = P.materials.fluid[0].c0;
  j["device_particles"] = r.slab_particles;
  j["device_busy_seconds"] = r.slab_busy_seconds;
  j["imbalance"] = r.imbalance;
  j["imbalance_history"] = r.imbalance_history;
  j["ghost_particles"] = r.ghosts;
  j["migrated_particles"] = r.migrated;
  j["handed_over_particles"] = r.handed_over;
  j["face_moves"] = r.face_moves;
  j["last_checkpoint"] = r.last_checkpoint.string();
  j["insitu_failures"] = r.insitu_failures;
  j["steering"] = {{"accepted", r.steering_accepted}, {"rejected", r.steering_rejected}, {"stopped", r.stopped_by_steering}};
  j["removed_particles"] = r.removed;
  j["removed_fraction"] = r.particles.fluid > 0 ? static_cast<double>(r.removed) / static_cast<double>(r.particles.fluid) : 0.0;
  j["removed_first_ids"] = r.removed_first_ids;
  if (c.closed_volume) j["closed_volume_scalings"] = r.closed_volume_scalings;
  j["exit_status"] = r.exit_status;
  j["exit_code"] = r.exit_code;
  if (!r.message.empty()) j["message"] = r.message;
  write_json(path, j);
}

void write_refusal_summary(const std::filesystem::path& path, const std::string& case_name, const std::string& case_file,
                           const std::string& exit_status, int exit_code, const std::string& message) {
  nlohmann::ordered_json j = summary_head(case_name, case_file);
  j["exit_status"] = exit_status;
  j["exit_code"] = exit_code;
  j["message"] = message;
  write_json(path, j);
}

}  // namespace spate
