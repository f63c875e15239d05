#pragma once
// A stand-in for a GPU's copy engine in the halo-protocol tests (unit and MPI): host memory plays
// every device's memory, memcpy every copy, and the copies are counted. Which devices reach each
// other by peer copies is the test's choice (all of them by default).
#include <cstring>
#include <functional>
#include <utility>
#include <vector>

#include "backend/cuda/halo_exchange.hpp"

namespace spate::gpu {

class HostCopies final : public DeviceCopies {
 public:
  explicit HostCopies(int device, std::function<bool(int, int)> reach = [](int, int) { return true; })
      : device_(device), reach_(std::move(reach)) {}
  int device() const override { return device_; }
  bool peer_both_ways(int other) override { return reach_(device_, other) && reach_(other, device_); }
  void wait_staged() override { fenced_ = false; }  // the first call of every exchange
  void copy_to_host(void* host, const void* device, std::size_t bytes) override {
    std::memcpy(host, device, bytes);
    ++to_host;
  }
  void copy_from_host(void* device, const void* host, std::size_t bytes) override {
    std::memcpy(device, host, bytes);
    ++from_host;
  }
  void copy_peer(void* device, const void* theirs, int their_device, std::size_t bytes) override {
    std::memcpy(device, theirs, bytes);
    ++peer;
    peer_from.push_back(their_device);
  }
  void after_incoming_read() override { fenced_ = true; }
  void wait_incoming_read() override {}
  void wait_copies() override {}
  // A device grows an incoming buffer in the copy stream's order, which must already wait for the
  // readers of the old one: asked for before after_incoming_read(), that would be a race.
  void* incoming(Side side, std::size_t bytes) override {
    if (!fenced_) ++unfenced_incoming;
    in[side].resize(bytes);
    return in[side].data();
  }
  void* pinned(int which, std::size_t bytes) override {
    if (staging[which].size() < bytes) staging[which].resize(bytes);
    return staging[which].data();
  }
  std::vector<char> in[2], staging[4];
  int to_host = 0, from_host = 0, peer = 0, unfenced_incoming = 0;
  std::vector<int> peer_from;

 private:
  int device_;
  std::function<bool(int, int)> reach_;
  bool fenced_ = false;
};

}  // namespace spate::gpu
