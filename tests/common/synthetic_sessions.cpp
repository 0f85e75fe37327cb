#include "synthetic_sessions.hpp"

#include <limits>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ivoa/dataset/dataset_format.hpp"

namespace ivoa::test {
namespace {

cv::Mat pattern(int label, std::mt19937& rng) {
  std::uniform_int_distribution<int> colour(40, 215), phase(0, 9);
  cv::Mat p(100, 100, CV_8UC3, cv::Scalar(colour(rng), colour(rng), colour(rng)));
  const int ph = phase(rng);
  for (int i = ph; i < 100; i += 10) {
    if (label == 0) cv::line(p, {0, i}, {99, i}, cv::Scalar(255, 255, 255), 3);  // horizontal stripes
    if (label == 1) cv::line(p, {i, 0}, {i, 99}, cv::Scalar(0, 0, 0), 3);        // vertical stripes
  }
  if (label == 2) cv::circle(p, {50, 50}, 20 + ph, cv::Scalar(255, 255, 255), -1);  // a bright blob
  cv::Mat noise(p.size(), CV_8UC3);
  cv::randn(noise, 0, label == 3 ? 40 : 8);  // 3: noise only
  return p + noise;
}

std::vector<float> evidence_of(int label, int size) {
  std::vector<float> evidence;
  for (int j = 0; j < size; ++j)
    evidence.push_back(j == 2 ? std::numeric_limits<float>::quiet_NaN() : 0.5f * static_cast<float>(label) + 0.1f * j);
  return evidence;
}

}  // namespace

void write_synthetic_session(const std::string& dataset_root, const std::string& name, const SyntheticSession& s) {
  std::mt19937 rng(s.seed);
  dataset::SessionInfo info;
  info.session = name;
  info.detector = s.detector;
  info.labels_from = "rerun";
  info.evidence_size = s.evidence_size;
  info.patch_scale = s.patch_scale;
  info.views = s.views;
  info.patch_size = s.patch_size;
  info.scene = s.scene;
  info.seed = s.scene_seed;
  info.image_size = s.image_size;
  dataset::SessionWriter w(dataset_root, info);
  const int64_t frame = w.add_frame(0, 0, 4 * s.per_class);
  for (int k = 0; k < s.per_class; ++k)
    for (int label = 0; label < 4; ++label) {
      dataset::SampleRecord sample;
      sample.frame = frame;
      sample.u = kSyntheticCellU;
      sample.v = kSyntheticCellV;
      sample.label = label;
      sample.stereo_state = label == 0 || label == 2 ? 1 : 0;  // TP / FP: the detector said obstacle
      cv::Mat patch = pattern(label, rng);
      if (s.patch_size != patch.cols) cv::resize(patch, patch, {s.patch_size, s.patch_size}, 0, 0, cv::INTER_AREA);
      if (s.views == 2) cv::vconcat(patch, patch.clone(), patch);
      w.add_sample(sample, patch, evidence_of(label, s.evidence_size));
    }
}

}  // namespace ivoa::test
