#pragma once
// The processes of one run. Launched by mpirun with several ranks, MPI is initialised and every
// process is one rank; launched plainly (or by mpirun with one rank) the run is one process that
// never calls MPI, so a single-process run needs no MPI runtime.
namespace spate {

struct ProcessGroup {
  int rank = 0;
  int ranks = 1;
  int ranks_on_node = 1;  // processes sharing this machine's cores
  bool mpi = false;       // MPI was initialised (ranks > 1)
};

// Once, first thing in main, before any thread starts. Throws std::runtime_error when the launcher
// asks for several ranks but this build has no MPI.
const ProcessGroup& init_process_group(int& argc, char**& argv);
const ProcessGroup& process_group();
// MPI_Finalize after a run every rank finished the same way.
void finalize_process_group();
// Ends every rank with `exit_code`: MPI_Abort when MPI is up, so that peers waiting in a
// collective do not hang; std::exit otherwise.
[[noreturn]] void abort_process_group(int exit_code);

}  // namespace spate
