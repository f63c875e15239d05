#pragma once
// What the solver process and its in-situ helper say to each other: one JSON object per packet of a
// SOCK_SEQPACKET socket pair (packets keep their boundaries, so there are no partial messages).
//
//   solver -> helper                          helper -> solver
//   init {scripts, ids, working_dir,           ready | error {message}
//         constants, arena, live?}
//   step {step, time, slabs, skip}             started {id}, finished {id} (per script, as it runs),
//                                              done {adaptor_seconds, script_seconds, failures,
//                                                    steering}
//                                              live_timeout {message} (then it exits)
//   finish                                     finished_all
//
// Slabs travel as addresses in the shared particle arena (particle_memory.hpp): the helper maps
// the arena at the same address, so the addresses are valid there as they are.
#include <nlohmann/json.hpp>

#include <vector>

#include "sim/insitu.hpp"

namespace spate::catalyst::wire {

// Sends one message; false when the peer is gone.
bool send(int fd, const nlohmann::json& message);

enum class Received { kMessage, kTimeout, kClosed };
// Waits up to timeout_seconds (< 0: for ever) for one message.
Received receive(int fd, nlohmann::json& message, double timeout_seconds);

nlohmann::json slabs_to_json(const std::vector<SlabView>& slabs);
// `shift` is added to every address (non-zero only when the helper could not map the arena at
// the solver's address).
std::vector<SlabView> slabs_from_json(const nlohmann::json& slabs, std::intptr_t shift);

}  // namespace spate::catalyst::wire
