#include "point_check_scoring.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

namespace ivoa::stereo_eval {

void JppPointModel::set_pair(const cv::Mat& left_gray, const cv::Mat& right_gray) {
  matcher_.set_images(left_gray, right_gray);
}

std::optional<PointCheckModel::Check> JppPointModel::check(cv::Point left, double disparity) {
  const cv::Point right(static_cast<int>(std::lround(left.x - disparity)), left.y);
  if (right.x < 0 || right.x >= matcher_.size().width) return std::nullopt;
  double cost = 0;
  const stereo::PointCheck verdict = matcher_.confident_positive(left, right, &cost);
  if (verdict == stereo::PointCheck::kUnobserved) return std::nullopt;
  return Check{verdict == stereo::PointCheck::kMatch, cost};
}

void SgbmPointModel::set_pair(const cv::Mat& left_gray, const cv::Mat& right_gray) {
  disparity_ = sgbm_.compute(left_gray, right_gray);
}

std::optional<PointCheckModel::Check> SgbmPointModel::check(cv::Point left, double disparity) {
  if (left.x - disparity < 0) return std::nullopt;
  const double distance = std::abs(disparity_.at<float>(left) - disparity);  // NaN where SGBM has none
  return Check{distance <= tolerance_, distance};
}

cv::Mat texture_energy(const cv::Mat& gray, int half_window) {
  cv::Mat image, dx;
  gray.convertTo(image, CV_32F);
  const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.f, 0.5f);
  cv::filter2D(image, dx, CV_32F, kx, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  cv::Mat energy;
  cv::boxFilter(dx.mul(dx), energy, CV_32F, cv::Size(2 * half_window + 1, 2 * half_window + 1));
  cv::sqrt(energy, energy);
  return energy;
}

ModelScore score(PointCheckModel& model, const cv::Mat& left_gray, const cv::Mat& right_gray, const cv::Mat& truth,
                 const ScoringOptions& options, cv::Mat* outcome_overlay) {
  CV_Assert(truth.type() == CV_32F && truth.size() == left_gray.size());
  model.set_pair(left_gray, right_gray);
  const cv::Mat energy = texture_energy(left_gray, options.texture_window);
  if (outcome_overlay) cv::cvtColor(left_gray / 2, *outcome_overlay, cv::COLOR_GRAY2BGR);
  ModelScore result;
  result.model = model.name();
  for (int v = 0; v < truth.rows; v += options.stride) {
    for (int u = 0; u < truth.cols; u += options.stride) {
      const float d = truth.at<float>(v, u);
      if (!std::isfinite(d)) continue;
      const auto truth_check = model.check({u, v}, d);
      if (!truth_check) continue;
      const bool textured = energy.at<float>(v, u) >= options.texture_threshold;
      TextureClassScore& cls = textured ? result.textured : result.untextured;
      ++cls.pixels;
      cls.at_truth.add(truth_check->confirmed);
      if (std::isfinite(truth_check->cost)) {
        cls.cost_sum_truth += truth_check->cost;
        ++cls.cost_count_truth;
      }
      for (int k : options.wrong_offsets) {
        for (int offset : {-k, k}) {
          const auto wrong = model.check({u, v}, d + offset);
          if (!wrong) continue;
          cls.wrong.add(wrong->confirmed);
          cls.by_offset[offset].add(wrong->confirmed);
          if (std::isfinite(wrong->cost)) {
            cls.cost_sum_wrong += wrong->cost;
            ++cls.cost_count_wrong;
          }
          if (std::isfinite(truth_check->cost) && std::isfinite(wrong->cost))
            cls.truth_cheaper.add(truth_check->cost < wrong->cost);
        }
      }
      if (outcome_overlay) {
        // Green: truth confirmed; red: truth rejected; dimmer where untextured.
        const auto level = static_cast<uint8_t>(textured ? 255 : 110);
        outcome_overlay->at<cv::Vec3b>(v, u) = truth_check->confirmed ? cv::Vec3b(0, level, 0) : cv::Vec3b(0, 0, level);
      }
    }
  }
  return result;
}

namespace {

void json_rate(std::ostringstream& out, const char* key, const Rate& r) {
  out << "\"" << key << "\": {\"tested\": " << r.tested << ", \"confirmed\": " << r.confirmed << ", \"rate\": ";
  if (r.tested > 0) out << r.value();
  else out << "null";  // nothing tested: no rate
  out << "}";
}

void json_class(std::ostringstream& out, const char* key, const TextureClassScore& c) {
  out << "\"" << key << "\": {\"pixels\": " << c.pixels << ", ";
  json_rate(out, "at_truth", c.at_truth);
  out << ", ";
  json_rate(out, "wrong", c.wrong);
  out << ", ";
  json_rate(out, "truth_cheaper", c.truth_cheaper);
  out << ", \"mean_cost_truth\": ";
  if (c.cost_count_truth) out << c.mean_cost_truth();
  else out << "null";
  out << ", \"mean_cost_wrong\": ";
  if (c.cost_count_wrong) out << c.mean_cost_wrong();
  else out << "null";
  out << ", \"by_offset\": {";
  bool first = true;
  for (const auto& [offset, rate] : c.by_offset) {
    out << (first ? "" : ", ");
    first = false;
    json_rate(out, std::to_string(offset).c_str(), rate);
  }
  out << "}}";
}

}  // namespace

std::string to_json(const std::vector<ModelScore>& scores, const ScoringOptions& options) {
  std::ostringstream out;
  out << "{\"stride\": " << options.stride << ", \"texture_threshold\": " << options.texture_threshold
      << ", \"wrong_offsets\": [";
  for (size_t i = 0; i < options.wrong_offsets.size(); ++i) out << (i ? ", " : "") << options.wrong_offsets[i];
  out << "], \"models\": {";
  for (size_t i = 0; i < scores.size(); ++i) {
    out << (i ? ", " : "") << "\"" << scores[i].model << "\": {";
    json_class(out, "textured", scores[i].textured);
    out << ", ";
    json_class(out, "untextured", scores[i].untextured);
    out << "}";
  }
  out << "}}\n";
  return out.str();
}

std::string to_table(const std::vector<ModelScore>& scores) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%-6s %-11s %8s %16s %16s %14s %11s  %s\n", "model", "pixels", "count",
                "truth confirmed", "wrong confirmed", "truth cheaper", "mean cost", "wrong confirmed by offset");
  out << line;
  // A rate nothing was tested for (every wrong offset off the image) is n/a, not 0 %.
  const auto percent = [](const Rate& r) {
    char cell[16];
    if (r.tested == 0) return std::string("n/a");
    std::snprintf(cell, sizeof(cell), "%.1f%%", 100.0 * r.value());
    return std::string(cell);
  };
  auto row = [&](const std::string& model, const char* label, const TextureClassScore& c) {
    std::string by_offset;
    for (const auto& [offset, rate] : c.by_offset) by_offset += fmt::format("{:+d}:{} ", offset, percent(rate));
    const auto cost = [](int64_t n, double mean) { return n ? fmt::format("{:5.2f}", mean) : std::string("  n/a"); };
    const std::string costs =
        cost(c.cost_count_truth, c.mean_cost_truth()) + "/" + cost(c.cost_count_wrong, c.mean_cost_wrong());
    std::snprintf(line, sizeof(line), "%-6s %-11s %8lld %16s %16s %14s %11s  %s\n", model.c_str(), label,
                  static_cast<long long>(c.pixels), percent(c.at_truth).c_str(), percent(c.wrong).c_str(),
                  percent(c.truth_cheaper).c_str(), costs.c_str(), by_offset.c_str());
    out << line;
  };
  for (const ModelScore& s : scores) {
    row(s.model, "textured", s.textured);
    row(s.model, "untextured", s.untextured);
  }
  return out.str();
}

}  // namespace ivoa::stereo_eval
