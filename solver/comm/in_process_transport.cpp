#include "in_process_transport.hpp"

#include <algorithm>

namespace spate {

class InProcessTransport final : public SlabTransport {
 public:
  InProcessTransport(InProcessHub& hub, int slab) : hub_(hub), slab_(slab) {}
  int slab() const override { return slab_; }
  int slab_count() const override { return hub_.slabs_; }

  void exchange(const Bytes& to_left, const Bytes& to_right, Bytes& from_left, Bytes& from_right) override {
    hub_.to_left_[slab_] = to_left;
    hub_.to_right_[slab_] = to_right;
    hub_.wait();
    const int l = left_of(slab_), r = right_of(slab_);
    from_left = l >= 0 ? hub_.to_right_[l] : Bytes{};
    from_right = r >= 0 ? hub_.to_left_[r] : Bytes{};
    hub_.wait();
  }
  void post(Bytes to_left, Bytes to_right) override {
    const int l = left_of(slab_), r = right_of(slab_);
    std::unique_lock lock(hub_.post_mutex_);
    const std::uint64_t k = hub_.posts_[slab_];
    wait_for(lock, [&] { return k < 2 || ((l < 0 || hub_.collects_[l] + 1 >= k) && (r < 0 || hub_.collects_[r] + 1 >= k)); });
    auto& box = hub_.mailbox_[k % 2][slab_];
    box.to_left = std::move(to_left);
    box.to_right = std::move(to_right);
    ++hub_.posts_[slab_];
    hub_.post_cv_.notify_all();
  }
  void collect(Bytes& from_left, Bytes& from_right) override {
    const int l = left_of(slab_), r = right_of(slab_);
    std::unique_lock lock(hub_.post_mutex_);
    const std::uint64_t k = hub_.collects_[slab_];
    wait_for(lock, [&] { return (l < 0 || hub_.posts_[l] > k) && (r < 0 || hub_.posts_[r] > k); });
    // Each mailbox side has exactly one reader, so it can be moved out.
    from_left = l >= 0 ? std::move(hub_.mailbox_[k % 2][l].to_right) : Bytes{};
    from_right = r >= 0 ? std::move(hub_.mailbox_[k % 2][r].to_left) : Bytes{};
    ++hub_.collects_[slab_];
    hub_.post_cv_.notify_all();
  }
  double min(double v) override {
    return reduce_double(v, [](double a, double b) { return std::min(a, b); });
  }
  double max(double v) override {
    return reduce_double(v, [](double a, double b) { return std::max(a, b); });
  }
  std::int64_t sum(std::int64_t v) override {
    hub_.islot_[slab_] = v;
    hub_.wait();
    std::int64_t s = 0;
    for (auto x : hub_.islot_) s += x;
    hub_.wait();
    return s;
  }
  void sum(std::vector<std::int64_t>& v) override {
    hub_.vslot_[slab_] = v;
    hub_.wait();
    std::fill(v.begin(), v.end(), 0);
    for (auto& other : hub_.vslot_)
      for (std::size_t k = 0; k < v.size(); ++k) v[k] += other[k];
    hub_.wait();
  }
  std::vector<Bytes> allgather(const Bytes& mine) override {
    hub_.gslot_[slab_] = mine;
    hub_.wait();
    std::vector<Bytes> all = hub_.gslot_;
    hub_.wait();
    return all;
  }
  std::vector<Bytes> gather(Bytes mine) override {
    hub_.gslot_[slab_] = std::move(mine);
    hub_.wait();
    std::vector<Bytes> all;
    if (slab_ == 0) {
      all = std::move(hub_.gslot_);  // the other slabs only touch the slots after the next barrier
      hub_.gslot_.assign(hub_.slabs_, Bytes{});
    }
    hub_.wait();
    return all;
  }
  void barrier() override { hub_.wait(); }
  bool any(bool flag) override { return max(flag ? 1.0 : 0.0) > 0.0; }

 private:
  template <class Op>
  double reduce_double(double v, Op op) {
    hub_.dslot_[slab_] = v;
    hub_.wait();
    double r = hub_.dslot_[0];
    for (int s = 1; s < hub_.slabs_; ++s) r = op(r, hub_.dslot_[s]);
    hub_.wait();
    return r;
  }
  template <class Ready>
  void wait_for(std::unique_lock<std::mutex>& lock, Ready ready) {
    hub_.post_cv_.wait(lock, [&] { return hub_.failed_.load() || ready(); });
    if (hub_.failed_) throw PeerFailure();
  }
  InProcessHub& hub_;
  int slab_;
};

InProcessHub::InProcessHub(int slabs)
    : slabs_(slabs),
      barrier_(slabs),
      to_left_(slabs),
      to_right_(slabs),
      dslot_(slabs),
      islot_(slabs),
      vslot_(slabs),
      gslot_(slabs),
      mailbox_{std::vector<Mailbox>(slabs), std::vector<Mailbox>(slabs)},
      posts_(slabs, 0),
      collects_(slabs, 0) {}

std::unique_ptr<SlabTransport> InProcessHub::endpoint(int slab, bool periodic_x) {
  auto t = std::make_unique<InProcessTransport>(*this, slab);
  t->periodic_x = periodic_x;
  return t;
}

void InProcessHub::wait() {
  if (failed_) throw PeerFailure();
  barrier_.arrive_and_wait();
  if (failed_) throw PeerFailure();
}

void InProcessHub::abandon() {
  {
    std::lock_guard lock(post_mutex_);
    failed_ = true;
  }
  post_cv_.notify_all();
  barrier_.arrive_and_drop();
}

}  // namespace spate
