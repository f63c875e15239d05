#include "post.hpp"

#include <algorithm>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "../case/generator.hpp"
#include "../comm/in_process_transport.hpp"
#include "../io/checkpoint.hpp"
#include "../io/vtk_snapshot.hpp"
#include "rigid_bodies.hpp"
#include "slab_worker.hpp"

namespace spate {

namespace {

// step_00000120.vtm, checkpoint_step_00000120.h5 -> 120; -1 when the name has no step.
std::int64_t step_of(const std::filesystem::path& file) {
  static const std::regex pattern("step_([0-9]+)");
  std::smatch m;
  const std::string name = file.filename().string();
  return std::regex_search(name, m, pattern) ? std::stoll(m[1]) : -1;
}

// All pieces as one store (a slab's worth of particles each; their order is kept).
ParticleStore merged(const std::vector<ParticleStore>& pieces, int dim) {
  ParticleStore all(dim);
  std::size_t n = 0;
  for (auto& p : pieces) n += p.owned();
  all.resize(n);
  auto to = all.fields();
  std::size_t at = 0;
  for (auto& piece : pieces) {
    auto from = const_cast<ParticleStore&>(piece).fields();
    for (std::size_t f = 0; f < to.size(); ++f)
      if (from[f].bytes() && to[f].bytes())
        std::copy_n(from[f].bytes(), piece.owned() * from[f].elem_size, to[f].bytes() + at * to[f].elem_size);
    at += piece.owned();
  }
  all.set_owned(n);
  return all;
}

}  // namespace

std::vector<SavedStep> saved_steps(const std::filesystem::path& run_dir, SavedKind kind) {
  std::vector<SavedStep> out;
  if (kind == SavedKind::Snapshot) {
    for (auto& [time, file] : read_pvd(run_dir / "particles.pvd")) out.push_back({kind, run_dir / file, step_of(file), time});
    return out;
  }
  const auto dir = run_dir / "checkpoints";
  std::error_code ec;
  for (auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".h5" && step_of(e.path()) >= 0) out.push_back({kind, e.path(), step_of(e.path())});
  std::sort(out.begin(), out.end(), [](const SavedStep& a, const SavedStep& b) { return a.step < b.step; });
  return out;
}

SavedState load_saved(const SavedStep& s, int dim) {
  SavedState state;
  if (s.kind == SavedKind::Checkpoint) {
    ParticleStore p;
    const CheckpointMeta meta = read_checkpoint(s.file, p);
    if (p.dim() != dim)
      throw std::runtime_error(s.file.string() + ": a " + std::to_string(p.dim()) + "D checkpoint, the case is " + std::to_string(dim) + "D");
    state.time = meta.time;
    state.step = meta.step;
    state.derived_saved = meta.derived_saved;
    state.case_yaml = meta.case_yaml;
    state.bodies = meta.bodies;
    state.pieces.push_back(std::move(p));
    state.slabs = {0};
    return state;
  }
  Snapshot snap = read_snapshot(s.file, dim);
  // Snapshots written before they had field data: the time from the index, the step from the name.
  state.time = snap.value("time", s.time);
  state.step = static_cast<std::int64_t>(snap.value("step", static_cast<double>(s.step)));
  state.pieces = std::move(snap.pieces);
  state.slabs = std::move(snap.slabs);
  state.field_data = std::move(snap.field_data);
  state.slab_count = static_cast<int>(state.pieces.size());
  for (int slab : state.slabs) state.slab_count = std::max(state.slab_count, slab + 1);
  return state;
}

Case run_case(const std::filesystem::path& run_dir, const std::vector<std::string>& overrides) {
  const auto file = run_dir / "case.yaml";
  if (std::filesystem::exists(file)) return load_case(file.string(), overrides);
  // Runs of earlier versions: the effective case a checkpoint holds.
  for (auto& s : saved_steps(run_dir, SavedKind::Checkpoint)) {
    ParticleStore ignored;
    try {
      const CheckpointMeta meta = read_checkpoint(s.file, ignored);
      if (!meta.case_yaml.empty()) return parse_case(meta.case_yaml, s.file.string() + " (case_yaml)", overrides);
    } catch (const std::runtime_error&) {
      continue;
    }
  }
  throw CaseError(run_dir.string() + ": not a spate run folder (no case.yaml, and no checkpoint that holds the case)");
}

SavedProbes::SavedProbes(const Case& c, const std::filesystem::path& out_dir, const std::vector<SteeringChange>& steering)
    : case_(c), probes_(c, out_dir, true, false), motions_(c.motions, c.dim) {
  // A motion keeps every change as a segment from its time on, so the whole log applied at once
  // gives the motion of any saved time (steering.cpp applies them during the run the same way).
  SteeringTarget target{nullptr, nullptr, &motions_};
  for (const SteeringChange& change : steering) {
    if (change.name != "motion_amplitude" && change.name != "motion_frequency") continue;
    if (auto why = validate(change, c.dim, &motions_)) throw std::runtime_error("steering log, step " + std::to_string(change.step) + ": " + *why);
    apply(change, target);
  }
}

SavedProbes::~SavedProbes() = default;

std::vector<std::vector<double>> SavedProbes::sample(const SavedState& s) {
  // One slab over the whole domain: probes do not depend on the split (probes.hpp), and the sort
  // puts the particles in the run's (cell, id) order, so every sum adds up in the same order.
  const Lattice lattice = make_lattice(case_);
  InProcessHub hub(1);
  auto transport = hub.endpoint(0, lattice.periodic[0]);
  // Moving walls where the run's motions (steered ones included) put them at that time: probes
  // that follow a body, the wall state of an old checkpoint.
  PhysicsParams P = physics_params(case_);
  motions_.set_step(P, s.time, s.time);
  // The floating solids as saved (body probes; the wall state of an old checkpoint); none in a
  // snapshot written before snapshots held them (their body probes are NaN).
  std::optional<RigidBodies> bodies;
  const std::string text = s.bodies.empty() ? RigidBodies::text_from(case_, s.field_data) : s.bodies;
  if (!text.empty()) {
    bodies.emplace(case_);
    bodies->restore(text);
    bodies->set_step(P);
  }
  SlabWorker w(lattice, P, *transport);
  w.take_share(merged(s.pieces, case_.dim), SlabLayout::uniform(lattice.cells[0], 1));
  if (s.derived_saved) w.prepare_saved();
  else w.prepare(false);
  return probes_.sample(s.time, s.step, w, &motions_, bodies ? &*bodies : nullptr);
}

}  // namespace spate
