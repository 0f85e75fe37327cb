#pragma once
// The side task of training: from the trunk's features, a linear head
// regresses the detector's evidence for the sample (dataset
// SessionInfo::evidence_size values: JPP-C's window cost at each ground
// sample of the footprint). The four-class label says only which side of
// its threshold JPP-C's worst sample fell; the costs say where every sample
// fell and by how much, which shapes the features that compare the two
// views. Only training uses the head: model files do not contain it.
#include <string>
#include <vector>

#include <torch/torch.h>

namespace ivoa::introspection {

class EvidenceTask {
 public:
  EvidenceTask(int64_t features, int64_t evidence_size, torch::Device device);

  // Mean squared error over the measured targets (NaN: not measured) of a
  // batch: features [B, F], targets [B, evidence_size].
  torch::Tensor loss(const torch::Tensor& features, const torch::Tensor& targets);

  std::vector<torch::Tensor> parameters() const { return head_->parameters(); }
  std::string bytes() const;  // the head's file, as load() reads it
  void load(const std::string& path);

 private:
  torch::nn::Linear head_;
};

}  // namespace ivoa::introspection
