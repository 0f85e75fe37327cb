#pragma once
// The four introspection labels of Algorithm 1, in the order of
// introspection_labels_t's LABEL_TP = 0, LABEL_TN, LABEL_FP, LABEL_FN: the
// order of every class axis (datasets, models, confusion matrices, figures).
#include <array>

namespace ivoa {

inline constexpr int kNumLabels = 4;
inline constexpr std::array<const char*, kNumLabels> kLabelNames = {"TP", "TN", "FP", "FN"};

}  // namespace ivoa
