#include "ivoa/aravis_stereo/stereo_pairer.hpp"

#include <algorithm>
#include <cstdlib>

namespace ivoa::aravis_stereo {

StereoPairer::StereoPairer(const PairingOptions& options) : options_(options) {
  if (options_.max_pending == 0) options_.max_pending = 1;
}

std::optional<StereoPair> StereoPairer::add(CameraFrame frame) {
  const int self = index(frame.side);
  const auto step = ids_[self].observe(frame.frame_id);
  counts_.missed[self] += step.missed;

  if (last_paired_us_[self] && frame.pairing_time_us <= *last_paired_us_[self]) {
    ++counts_.out_of_order;
    return std::nullopt;
  }

  auto& others = pending_[1 - self];
  auto best = others.end();
  int64_t best_gap = 0;
  for (auto it = others.begin(); it != others.end(); ++it) {
    const int64_t gap = std::llabs(it->pairing_time_us - frame.pairing_time_us);
    if (best == others.end() || gap < best_gap) best = it, best_gap = gap;
  }
  if (best == others.end() || best_gap > options_.tolerance_us) {
    insert_pending(std::move(frame));
    return std::nullopt;
  }

  CameraFrame partner = std::move(*best);
  others.erase(best);
  StereoPair pair;
  if (frame.side == Side::kLeft) pair.left = std::move(frame), pair.right = std::move(partner);
  else pair.left = std::move(partner), pair.right = std::move(frame);
  last_paired_us_[0] = pair.left.pairing_time_us;
  last_paired_us_[1] = pair.right.pairing_time_us;
  // Anything pending at or before the pair can no longer be published in order.
  drop_pending_up_to(Side::kLeft, pair.left.pairing_time_us);
  drop_pending_up_to(Side::kRight, pair.right.pairing_time_us);
  ++counts_.pairs;
  return pair;
}

void StereoPairer::insert_pending(CameraFrame frame) {
  auto& queue = pending_[index(frame.side)];
  const auto at = std::upper_bound(queue.begin(), queue.end(), frame.pairing_time_us,
                                   [](int64_t t, const CameraFrame& f) { return t < f.pairing_time_us; });
  queue.insert(at, std::move(frame));
  while (queue.size() > options_.max_pending) {
    queue.pop_front();
    ++counts_.unpaired;
  }
}

void StereoPairer::drop_pending_up_to(Side side, int64_t time_us) {
  auto& queue = pending_[index(side)];
  while (!queue.empty() && queue.front().pairing_time_us <= time_us) {
    queue.pop_front();
    ++counts_.unpaired;
  }
}

void StereoPairer::reset(Side side) {
  const int i = index(side);
  counts_.unpaired += static_cast<int64_t>(pending_[i].size());
  pending_[i].clear();
  ids_[i].reset();
  last_paired_us_[i].reset();
}

}  // namespace ivoa::aravis_stereo
