#include "evidence_task.hpp"

#include <sstream>

namespace ivoa::introspection {

EvidenceTask::EvidenceTask(int64_t features, int64_t evidence_size, torch::Device device)
    : head_(features, evidence_size) {
  head_->to(device);
}

torch::Tensor EvidenceTask::loss(const torch::Tensor& features, const torch::Tensor& targets) {
  const auto measured = torch::isnan(targets).logical_not().to(torch::kFloat);
  const auto error = (head_->forward(features) - torch::nan_to_num(targets, 0.0)).pow(2) * measured;
  return error.sum() / measured.sum().clamp_min(1.0);
}

std::string EvidenceTask::bytes() const {
  std::ostringstream out;
  torch::save(head_, out);
  return out.str();
}

void EvidenceTask::load(const std::string& path) { torch::load(head_, path); }

}  // namespace ivoa::introspection
