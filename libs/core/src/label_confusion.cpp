#include "ivoa/core/label_confusion.hpp"

#include <limits>

namespace ivoa {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool is_label(int c) { return c >= 0 && c < LabelConfusion::kLabels; }

}  // namespace

void LabelConfusion::add(int label, int predicted) {
  if (is_label(label) && is_label(predicted)) ++counts[label][predicted];
}

int64_t LabelConfusion::count(int label) const {
  int64_t n = 0;
  for (const int64_t c : counts[label]) n += c;
  return n;
}

int64_t LabelConfusion::total() const {
  int64_t n = 0;
  for (int label = 0; label < kLabels; ++label) n += count(label);
  return n;
}

double LabelConfusion::recall(int label) const {
  const int64_t n = count(label);
  return n ? static_cast<double>(counts[label][label]) / static_cast<double>(n) : kNaN;
}

double LabelConfusion::mean_per_class() const {
  double sum = 0;
  int present = 0;
  for (int label = 0; label < kLabels; ++label)
    if (count(label)) sum += recall(label), ++present;
  return present ? sum / present : kNaN;
}

double LabelConfusion::overall() const {
  int64_t right = 0;
  for (int label = 0; label < kLabels; ++label) right += counts[label][label];
  const int64_t n = total();
  return n ? static_cast<double>(right) / static_cast<double>(n) : kNaN;
}

}  // namespace ivoa
