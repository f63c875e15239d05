#include "process_group.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#ifdef SPATE_WITH_MPI
#include <mpi.h>
#endif

namespace spate {

namespace {

ProcessGroup group;

// The launcher's view of the job, read from the environment so that MPI is only touched when it
// is really needed: OpenMPI's mpirun sets OMPI_COMM_WORLD_*, MPICH's Hydra PMI_*.
int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  try {
    return std::stoi(v);
  } catch (const std::exception&) {
    return fallback;
  }
}

int launched_ranks() {
  if (int n = env_int("OMPI_COMM_WORLD_SIZE", 0); n > 0) return n;
  if (int n = env_int("PMI_SIZE", 0); n > 0) return n;
  // A PMIx launcher that does not say the size: assume a real job and let MPI tell.
  if (std::getenv("PMIX_RANK")) return 2;
  return 1;
}

}  // namespace

const ProcessGroup& init_process_group(int& argc, char**& argv) {
  const int requested = launched_ranks();
  if (requested <= 1) return group;
#ifdef SPATE_WITH_MPI
  // Only the first device worker of a rank calls MPI, and it runs on the main thread; SERIALIZED
  // (one thread at a time, any thread) is still asked for so that this stays correct if the
  // worker ever moves to another thread.
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  if (provided < MPI_THREAD_SERIALIZED) {
    std::fprintf(stderr, "spate: error: the MPI library offers thread level %d, spate needs MPI_THREAD_SERIALIZED\n", provided);
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  // Errors in MPI calls abort the whole job with MPI's own message rather than returning codes
  // that a failing rank might not get to report.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_ARE_FATAL);
  MPI_Comm_rank(MPI_COMM_WORLD, &group.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &group.ranks);
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, group.rank, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &group.ranks_on_node);
  MPI_Comm_free(&node);
  group.mpi = true;
  return group;
#else
  (void)argc;
  (void)argv;
  throw std::runtime_error("launched as " + std::to_string(requested) +
                           " MPI ranks, but this spate was built without MPI (reconfigure with MPI found, SPATE_ENABLE_MPI=ON)");
#endif
}

const ProcessGroup& process_group() { return group; }

void finalize_process_group() {
#ifdef SPATE_WITH_MPI
  if (group.mpi) {
    MPI_Finalize();
    group.mpi = false;
  }
#endif
}

void abort_process_group(int exit_code) {
  std::fflush(stdout);
  std::fflush(stderr);
#ifdef SPATE_WITH_MPI
  if (group.mpi) MPI_Abort(MPI_COMM_WORLD, exit_code);
#endif
  std::exit(exit_code);
}

}  // namespace spate
