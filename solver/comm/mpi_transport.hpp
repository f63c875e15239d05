#pragma once
// Slabs spread over MPI ranks, D device workers per rank: global slab = rank * D + local device.
// Built only with SPATE_WITH_MPI; MPI must be initialised (init_process_group) before use.
#include <memory>

#include "transport.hpp"

namespace spate {

// This rank's D slabs. Collective over all ranks (every rank calls it with the same D).
std::unique_ptr<LocalSlabs> make_mpi_slabs(int local_slabs);

}  // namespace spate
