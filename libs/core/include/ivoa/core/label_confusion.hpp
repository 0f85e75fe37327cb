#pragma once
// A confusion matrix over the four introspection labels, and the paper's
// headline metric, its mean per-class accuracy. Training validation and the
// live scorer count with it; the Python report computes the same figures
// from ivoa-eval's predictions.
#include <array>
#include <cstdint>

#include "ivoa/core/labels.hpp"

namespace ivoa {

struct LabelConfusion {
  static constexpr int kLabels = kNumLabels;  // kLabelNames' order

  std::array<std::array<int64_t, kLabels>, kLabels> counts{};  // [true label][predicted]

  // Counts one prediction; a value outside 0..3 (LABEL_NONE) is not counted.
  void add(int label, int predicted);
  int64_t total() const;
  int64_t count(int label) const;  // samples with this true label
  double recall(int label) const;  // the label's accuracy; NaN if it has no samples
  double mean_per_class() const;   // mean recall over the labels present; NaN if empty
  double overall() const;          // NaN if empty
};

}  // namespace ivoa
