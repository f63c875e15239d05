#include "insitu_wire.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>
#include <chrono>
#include <set>
#include <string>

namespace spate::catalyst::wire {

namespace {

constexpr std::size_t kMaxMessage = 1 << 20;  // tracebacks are cut to fit (see the senders)

template <class T>
std::uintptr_t address(const T* p) {
  return reinterpret_cast<std::uintptr_t>(p);
}

template <class T>
const T* pointer(const nlohmann::json& j, std::intptr_t shift) {
  const auto a = j.get<std::uintptr_t>();
  return a ? reinterpret_cast<const T*>(a + shift) : nullptr;
}

}  // namespace

bool send(int fd, const nlohmann::json& message) {
  std::string text = message.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > kMaxMessage) return false;
  for (;;) {
    const ssize_t n = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(text.size())) return true;
    if (n < 0 && errno == EINTR) continue;
    return false;
  }
}

Received receive(int fd, nlohmann::json& message, double timeout_seconds) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                                           timeout_seconds < 0 ? 0.0 : timeout_seconds));
  for (;;) {
    int wait_ms = -1;
    if (timeout_seconds >= 0) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return Received::kTimeout;
      wait_ms = static_cast<int>(std::min<long long>(left, 1 << 30));
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = poll(&p, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return Received::kClosed;
    if (ready == 0) continue;  // the deadline check above decides
    thread_local std::string buffer(kMaxMessage, '\0');
    const ssize_t n = recv(fd, buffer.data(), buffer.size(), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Received::kClosed;
    message = nlohmann::json::parse(buffer.data(), buffer.data() + n, nullptr, /*allow_exceptions=*/false);
    if (message.is_discarded() || !message.is_object()) return Received::kClosed;  // not our peer
    return Received::kMessage;
  }
}

nlohmann::json slabs_to_json(const std::vector<SlabView>& slabs) {
  nlohmann::json out = nlohmann::json::array();
  for (const SlabView& v : slabs) {
    nlohmann::json s;
    s["slab"] = v.slab;
    s["slab_count"] = v.slab_count;
    s["dim"] = v.dim;
    s["owned"] = v.owned;
    s["fluids"] = v.fluids;
    s["pos"] = {address(v.pos[0]), address(v.pos[1]), address(v.pos[2])};
    s["arrays"] = nlohmann::json::array();
    for (const SlabArray& a : v.arrays)
      s["arrays"].push_back({{"name", a.name},
                             {"type", static_cast<int>(a.type)},
                             {"components", a.components},
                             {"data", {address(a.data[0]), address(a.data[1]), address(a.data[2])}}});
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<SlabView> slabs_from_json(const nlohmann::json& slabs, std::intptr_t shift) {
  // SlabArray names are views: the helper keeps every name it was sent for its whole life.
  static std::set<std::string, std::less<>> names;
  std::vector<SlabView> out;
  for (const auto& s : slabs) {
    SlabView v;
    v.slab = s.at("slab").get<int>();
    v.slab_count = s.at("slab_count").get<int>();
    v.dim = s.at("dim").get<int>();
    v.owned = s.at("owned").get<std::size_t>();
    v.fluids = s.value("fluids", 1);
    for (int k = 0; k < 3; ++k) v.pos[k] = pointer<float>(s.at("pos").at(k), shift);
    for (const auto& a : s.at("arrays")) {
      SlabArray array;
      array.name = *names.insert(a.at("name").get<std::string>()).first;
      array.type = static_cast<FieldType>(a.at("type").get<int>());
      array.components = a.at("components").get<int>();
      for (int k = 0; k < 3; ++k) array.data[k] = pointer<char>(a.at("data").at(k), shift);
      v.arrays.push_back(array);
    }
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace spate::catalyst::wire
