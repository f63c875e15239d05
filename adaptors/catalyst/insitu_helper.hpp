#pragma once
// The in-situ helper process: ParaView Catalyst, Python and the pipelines run here, not in the
// solver. spate starts it as `spate __insitu-helper SOCKET_FD ARENA_FD PARENT_PID` (the same
// binary, so that the two always match); it maps the solver's particle arena (read-only, at the
// solver's address: zero copy), runs the pipelines on the steps the solver sends, and reports each
// script's start, end, time and Python errors back (insitu_wire.hpp). Whatever a pipeline does to
// this process (a segfault, abort, exit, a hang, a lost display) ends at most this process; the
// solver blames the script that was running, switches it off and starts a fresh helper for the
// others (helper_process.hpp, catalyst_sink.cpp). It dies with the solver (PR_SET_PDEATHSIG).
namespace spate::catalyst {

inline constexpr const char* kHelperCommand = "__insitu-helper";
// The helper's exit status when a live peer accepted the connection but did not complete
// ParaView's handshake in time (it sends live_timeout first).
inline constexpr int kLiveHandshakeTimeoutExit = 86;

// The helper's main: argv[1] is kHelperCommand. Returns the process's exit status.
int run_insitu_helper(int argc, char** argv);

}  // namespace spate::catalyst
