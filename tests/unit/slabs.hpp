#pragma once
// Slab workers for the unit tests of whole-slab operations (probes, the held volume): one slab
// prepared as at the start of a run, or several sharing the particles along x, whose collective
// calls (exact sums over every slab) run on one thread per slab.
#include <memory>
#include <thread>
#include <vector>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "sim/slab_worker.hpp"

namespace spate::test {

// One slab holding `particles`, with pressures and wall states computed as at the start of a run.
struct OneSlab {
  OneSlab(const Case& c, const ParticleStore& particles) : lattice(make_lattice(c)), hub(1), t(hub.endpoint(0, false)),
                                                           w(lattice, physics_params(c), *t) {
    w.take_share(particles, SlabLayout::uniform(lattice.cells[0], 1));
    w.prepare(false);
  }
  Lattice lattice;
  InProcessHub hub;
  std::unique_ptr<SlabTransport> t;
  SlabWorker w;
};

// `n` slabs of a uniform layout sharing `particles`; each(f) calls f(slab index, worker) on a thread
// per slab and returns the results in slab order.
struct SplitSlabs {
  SplitSlabs(const Case& c, const ParticleStore& particles, int n) : lattice(make_lattice(c)), hub(n) {
    for (int s = 0; s < n; ++s) {
      t.push_back(hub.endpoint(s, false));
      w.push_back(std::make_unique<SlabWorker>(lattice, physics_params(c), *t[s]));
      w[s]->take_share(particles, SlabLayout::uniform(lattice.cells[0], n));
    }
  }
  template <class F>
  auto each(F&& f) {
    std::vector<decltype(f(0, *w[0]))> out(w.size());
    std::vector<std::thread> threads;
    for (std::size_t s = 0; s < w.size(); ++s) threads.emplace_back([&, s] { out[s] = f(static_cast<int>(s), *w[s]); });
    for (auto& th : threads) th.join();
    return out;
  }
  Lattice lattice;
  InProcessHub hub;
  std::vector<std::unique_ptr<SlabTransport>> t;
  std::vector<std::unique_ptr<SlabWorker>> w;
};

}  // namespace spate::test
