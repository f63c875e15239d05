#include "halo_exchange.hpp"

#include <atomic>
#include <cstring>
#include <stdexcept>
#include <string>

namespace spate::gpu {

HaloLink choose_halo_link(bool has_neighbour, bool shares_memory, int mine, int theirs, bool peer_both_ways,
                          bool cuda_aware_mpi, bool force_staged) {
  if (!has_neighbour) return HaloLink::None;
  if (!shares_memory) return cuda_aware_mpi ? HaloLink::DeviceMpi : HaloLink::Staged;
  if (force_staged) return HaloLink::Staged;
  return mine == theirs || peer_both_ways ? HaloLink::Peer : HaloLink::Staged;
}

bool staged_links_forced(const char* env) {
  const std::string v = env ? env : "";
  if (v.empty() || v == "auto") return false;
  if (v == "staged") return true;
  throw std::invalid_argument("SPATE_CUDA_HALO_LINK='" + v + "': expected auto or staged");
}

namespace {
std::atomic<std::uint64_t> peer_bytes{0}, staged_bytes{0}, device_mpi_bytes{0};

struct Header {
  std::uint64_t count = 0, bytes = 0, address = 0;
  std::int32_t device = -1;
};
}  // namespace

HaloTraffic halo_traffic() { return {peer_bytes.load(), staged_bytes.load(), device_mpi_bytes.load()}; }

// Once, at the first exchange (every slab makes its first at the same point): the devices.
void HaloExchange::discover(SlabTransport& t, DeviceCopies& copies) {
  const std::int32_t mine = copies.device();
  Bytes message(sizeof mine), got[2];
  std::memcpy(message.data(), &mine, sizeof mine);
  t.exchange(message, message, got[kLeft], got[kRight]);
  const int s = t.slab();
  for (Side side : {kLeft, kRight}) {
    const int neighbour = side == kLeft ? t.left_of(s) : t.right_of(s);
    const bool shares = neighbour >= 0 && t.shares_memory_with(neighbour);
    std::int32_t theirs = -1;
    if (got[side].size() == sizeof theirs) std::memcpy(&theirs, got[side].data(), sizeof theirs);
    const bool peer = shares && !force_staged_ && theirs != mine && theirs >= 0 && copies.peer_both_ways(theirs);
    links_[side] = choose_halo_link(neighbour >= 0, shares, mine, theirs, peer, cuda_aware_mpi_, force_staged_);
  }
  known_ = true;
}

std::array<std::size_t, 2> HaloExchange::exchange(SlabTransport& t, DeviceCopies& copies, const std::array<Outgoing, 2>& out) {
  if (!known_) discover(t, copies);
  copies.wait_staged();
  for (Side side : {kLeft, kRight})
    if (links_[side] == HaloLink::Staged && out[side].bytes > 0)
      copies.copy_to_host(copies.pinned(side, out[side].bytes), out[side].device, out[side].bytes);
  copies.wait_copies();
  Bytes message[2], got[2];
  for (Side side : {kLeft, kRight}) {
    const Header h{out[side].count, out[side].bytes, reinterpret_cast<std::uint64_t>(out[side].device), copies.device()};
    const bool payload = links_[side] == HaloLink::Staged;
    message[side].resize(sizeof h + (payload ? h.bytes : 0));
    std::memcpy(message[side].data(), &h, sizeof h);
    if (payload && h.bytes > 0) std::memcpy(message[side].data() + sizeof h, copies.pinned(side, h.bytes), h.bytes);
  }
  t.exchange(message[kLeft], message[kRight], got[kLeft], got[kRight]);
  copies.after_incoming_read();
  std::array<std::size_t, 2> counts{0, 0};
  SlabTransport::DeviceSpan span[2];
  for (Side side : {kLeft, kRight}) {
    if (got[side].size() < sizeof(Header)) continue;
    Header h;
    std::memcpy(&h, got[side].data(), sizeof h);
    counts[side] = h.count;
    void* in = copies.incoming(side, h.bytes);
    if (h.bytes == 0) continue;
    switch (links_[side]) {
      case HaloLink::Peer:
        copies.copy_peer(in, reinterpret_cast<const void*>(h.address), h.device, h.bytes);
        peer_bytes += h.bytes;
        break;
      case HaloLink::Staged: {
        if (got[side].size() != sizeof h + h.bytes) throw std::runtime_error("halo exchange: truncated payload");
        void* host = copies.pinned(2 + side, h.bytes);
        std::memcpy(host, got[side].data() + sizeof h, h.bytes);
        copies.copy_from_host(in, host, h.bytes);
        staged_bytes += h.bytes;
        break;
      }
      case HaloLink::DeviceMpi:
        span[side].recv = in;
        span[side].recv_bytes = h.bytes;
        device_mpi_bytes += h.bytes;
        break;
      case HaloLink::None:
        break;
    }
  }
  if (cuda_aware_mpi_) {
    // Collective on every slab of the process, whether or not this one has a remote side.
    bool remote = false;
    for (Side side : {kLeft, kRight})
      if (links_[side] == HaloLink::DeviceMpi) {
        span[side].send = out[side].device;
        span[side].send_bytes = out[side].bytes;
        remote = true;
      }
    if (remote) copies.wait_incoming_read();
    if (!t.exchange_device(span[kLeft], span[kRight]) && remote)
      throw std::runtime_error("SPATE_CUDA_AWARE_MPI: the transport cannot exchange device buffers");
  }
  copies.wait_copies();
  Bytes none[2];
  t.exchange(Bytes{}, Bytes{}, none[kLeft], none[kRight]);
  return counts;
}

}  // namespace spate::gpu
