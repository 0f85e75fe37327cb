#include "ivoa/aravis_stereo/stereo_pairer.hpp"

#include <algorithm>
#include <cstdlib>

namespace ivoa::aravis_stereo {

StereoPairer::StereoPairer(const PairingOptions& options) : options_(options) {
  if (options_.max_pending == 0) options_.max_pending = 1;
  if (options_.unlock_after_rejects < 1) options_.unlock_after_rejects = 1;
}

std::optional<StereoPair> StereoPairer::add(CameraFrame frame) {
  const int self = index(frame.side);
  const auto step = ids_[self].observe(frame.frame_id);
  counts_.missed[self] += step.missed;
  if (last_paired_us_[self] && frame.pairing_time_us <= *last_paired_us_[self]) {
    ++counts_.out_of_order;
    return std::nullopt;
  }
  Pending incoming{std::move(frame), step.sequence};
  return locked_ ? add_by_frame_id(std::move(incoming)) : add_by_time(std::move(incoming));
}

std::optional<StereoPair> StereoPairer::add_by_time(Pending incoming) {
  auto& others = pending_[1 - index(incoming.frame.side)];
  auto best = others.end();
  int64_t best_gap = 0;
  for (auto it = others.begin(); it != others.end(); ++it) {
    const int64_t gap = std::llabs(it->frame.pairing_time_us - incoming.frame.pairing_time_us);
    if (best == others.end() || gap < best_gap) best = it, best_gap = gap;
  }
  if (best == others.end() || best_gap > options_.tolerance_us) {
    insert_pending(std::move(incoming));
    return std::nullopt;
  }
  Pending partner = std::move(*best);
  others.erase(best);
  return emit(std::move(incoming), std::move(partner));
}

std::optional<StereoPair> StereoPairer::add_by_frame_id(Pending incoming) {
  const bool left = incoming.frame.side == Side::kLeft;
  const int64_t wanted = left ? incoming.sequence + offset_ : incoming.sequence - offset_;
  auto& others = pending_[left ? 1 : 0];
  const auto partner =
      std::find_if(others.begin(), others.end(), [&](const Pending& p) { return p.sequence == wanted; });
  if (partner == others.end()) {
    insert_pending(std::move(incoming));  // its partner may still come
    return std::nullopt;
  }
  if (std::llabs(partner->frame.pairing_time_us - incoming.frame.pairing_time_us) > options_.tolerance_us) {
    others.erase(partner);  // numbered as one trigger but not taken together: neither is published
    counts_.unpaired += 2;
    if (++rejects_ >= options_.unlock_after_rejects) unlock();
    return std::nullopt;
  }
  rejects_ = 0;
  Pending matched = std::move(*partner);
  others.erase(partner);
  return emit(std::move(incoming), std::move(matched));
}

StereoPair StereoPairer::emit(Pending a, Pending b) {
  if (a.frame.side != Side::kLeft) std::swap(a, b);
  if (!locked_ && options_.lock_after_pairs > 0) {
    const int64_t offset = b.sequence - a.sequence;
    agreeing_ = offset == candidate_ ? agreeing_ + 1 : 1;
    candidate_ = offset;
    if (agreeing_ >= options_.lock_after_pairs) {
      locked_ = true;
      offset_ = offset;
      rejects_ = 0;
    }
  }
  StereoPair pair{std::move(a.frame), std::move(b.frame)};
  last_paired_us_[0] = pair.left.pairing_time_us;
  last_paired_us_[1] = pair.right.pairing_time_us;
  // Anything pending at or before the pair can no longer be published in order.
  drop_pending_up_to(Side::kLeft, pair.left.pairing_time_us);
  drop_pending_up_to(Side::kRight, pair.right.pairing_time_us);
  ++counts_.pairs;
  return pair;
}

void StereoPairer::insert_pending(Pending frame) {
  auto& queue = pending_[index(frame.frame.side)];
  const auto at = std::upper_bound(queue.begin(), queue.end(), frame.frame.pairing_time_us,
                                   [](int64_t t, const Pending& p) { return t < p.frame.pairing_time_us; });
  queue.insert(at, std::move(frame));
  while (queue.size() > options_.max_pending) {
    queue.pop_front();
    ++counts_.unpaired;
  }
}

void StereoPairer::drop_pending_up_to(Side side, int64_t time_us) {
  auto& queue = pending_[index(side)];
  while (!queue.empty() && queue.front().frame.pairing_time_us <= time_us) {
    queue.pop_front();
    ++counts_.unpaired;
  }
}

void StereoPairer::unlock() {
  if (locked_) ++counts_.unlocks;
  locked_ = false;
  agreeing_ = 0;
  rejects_ = 0;
}

void StereoPairer::reset(Side side) {
  const int i = index(side);
  counts_.unpaired += static_cast<int64_t>(pending_[i].size());
  pending_[i].clear();
  ids_[i].reset();
  last_paired_us_[i].reset();
  // Its counter restarted, so the offset is void; not counted as an unlock.
  locked_ = false;
  agreeing_ = 0;
  rejects_ = 0;
}

}  // namespace ivoa::aravis_stereo
