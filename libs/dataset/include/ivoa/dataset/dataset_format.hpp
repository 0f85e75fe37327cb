#pragma once
// Writing and reading the on-disk dataset (see libs/dataset/README.md):
// per session a raw patch store (memory-mappable), a CSV index and JSON
// metadata.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/labels.hpp"
#include "ivoa/core/query_grid.hpp"

namespace ivoa::dataset {

inline constexpr int kNumClasses = kNumLabels;  // kLabelNames' order
inline constexpr int kUnknownSurface = 255;

class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SampleRecord {
  int64_t frame = 0;
  int64_t utime = 0;
  int64_t depth_utime = 0;
  int32_t cell = 0;
  int32_t label = 0;
  int32_t stereo_state = 0;
  int32_t depth_state = 0;
  float x = 0, y = 0;
  float u = 0, v = 0;
  int32_t phenomena = 0;
  int32_t phenomenon = 0;
  int32_t surface = kUnknownSurface;
  // Side in pixels of the square cut around (u, v) before it was resized to
  // the session's patch_size (SessionInfo::patch_scale); 0 in datasets
  // written before it was recorded, which means patch_size.
  int32_t patch_side = 0;
};

struct FrameRecord {
  int64_t utime = 0;
  int64_t depth_utime = 0;
  int32_t cells_labelled = 0;
  int32_t samples = 0;
};

struct SessionInfo {
  std::string session;
  std::string detector;
  std::string labels_from;  // "recorded" or "rerun"
  std::vector<std::string> logs;
  std::string scene;
  int64_t seed = -1;
  std::string environment = "unknown";  // indoor, outdoor, unknown
  std::string rig_name;
  // The left image's width x height in pixels, which the patches are cut
  // from; 0 x 0 in datasets written before it was recorded.
  cv::Size image_size;
  int patch_size = 100;
  // 1: the left image's patch (the paper); 2: the left patch with, below
  // it, the same square of the right image warped onto the ground plane
  // (core's GroundWarp). A stored patch is (views x patch_size) rows by
  // patch_size columns, 8-bit BGR.
  int views = 1;
  // 0: every patch is the patch_size square around its cell (the paper).
  // > 0: footprint-scaled patches (core's footprint_patch.hpp): squares of
  // this many footprint-disc widths, at least patch_size, resized to
  // patch_size; each sample records the side it was cut at.
  double patch_scale = 0;
  // < 1: only this fraction of the TN cells was stored, to save disk
  // (BuildOptions::keep_tn); class_counts count what was stored.
  double tn_kept = 1;
  // Values per sample in evidence.f32 (the detector's Evidence for the
  // sample's cell: JPP-C's 15 window costs); 0: the session has none.
  int evidence_size = 0;
  QueryGridConfig grid;
  // Filled by the writer / reader:
  int64_t frames = 0;
  int64_t samples = 0;
  std::array<int64_t, kNumClasses> class_counts{};
  int64_t tn_dropped = 0;  // TN cells left out (tn_kept < 1)
};

// Writes one session folder. Patches are appended as they come; close()
// (or the destructor) writes the index and metadata.
class SessionWriter {
 public:
  SessionWriter(const std::string& dataset_root, SessionInfo info);
  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  // Starts a frame; returns its index for the samples that follow.
  int64_t add_frame(int64_t utime, int64_t depth_utime, int32_t cells_labelled);
  // `patch` must be (views x patch_size) x patch_size CV_8UC3; `evidence`
  // must hold info().evidence_size values (NaN: not measured).
  void add_sample(SampleRecord sample, const cv::Mat& patch, const std::vector<float>& evidence = {});
  // A TN cell of the current frame left out (SessionInfo::tn_kept < 1).
  void count_dropped_tn() { ++info_.tn_dropped; }
  // A log read after the first sample was written (a split recording's later parts).
  void add_source_log(std::string path) { info_.logs.push_back(std::move(path)); }
  void close();
  // Closes and removes what was written without registering it: a build
  // that failed part-way leaves the dataset as it was (a session of that
  // name built before stays whole). A session close() built whole but could
  // not put in place stays where its error says.
  void abandon();
  const SessionInfo& info() const { return info_; }

 private:
  struct Files;
  void write_evidence(const std::vector<float>& evidence);
  void replace_session_folder();
  std::string dir_;             // the session's folder
  std::string work_dir_;        // written here, renamed to dir_ by close(): a failed rebuild keeps the old session
  bool keep_work_dir_ = false;  // built whole, not put in place: the user is told where it is
  SessionInfo info_;
  std::unique_ptr<Files> files_;
  std::vector<FrameRecord> frames_;
};

// Reads one session folder; patches are memory-mapped.
class SessionReader {
 public:
  explicit SessionReader(const std::string& session_dir);  // throws DatasetError
  ~SessionReader();
  SessionReader(const SessionReader&) = delete;
  SessionReader& operator=(const SessionReader&) = delete;

  const SessionInfo& info() const { return info_; }
  const std::vector<SampleRecord>& samples() const { return samples_; }
  size_t size() const { return samples_.size(); }
  // A view of patch i, all its views stacked (no copy; valid while the reader lives).
  cv::Mat patch(size_t i) const;
  // Its left-image square only (pictures, mosaics).
  cv::Mat left_patch(size_t i) const { return patch(i).rowRange(0, info_.patch_size); }
  size_t patch_bytes() const;
  const uint8_t* patch_data(size_t i) const;
  // Asks the kernel to start reading patches [first, first + count) from
  // disk; a hint, for readers that know which patches come next (a batch).
  void prefetch(size_t first, size_t count = 1) const;
  // The info().evidence_size evidence values of sample i; nullptr if the
  // session has none.
  const float* evidence(size_t i) const;

 private:
  void check_index_matches_metadata() const;
  void read_evidence();
  std::string dir_;
  SessionInfo info_;
  std::vector<SampleRecord> samples_;
  std::vector<float> evidence_;
  const uint8_t* mapped_ = nullptr;
  size_t mapped_bytes_ = 0;
};

// dataset.json: the list of sessions and the patch size; replaced, under a
// lock, when a session is added, so builds may add sessions side by side.
void register_session(const std::string& dataset_root, const std::string& session, int patch_size);
std::vector<std::string> list_sessions(const std::string& dataset_root);

// Throws DatasetError unless `name` can name a session: a folder name (not
// empty, no '/', not starting with '.', which the builder's own folders
// do) that the CSV files it is written into need not quote (no ',', '"' or
// control characters).
void check_session_name(const std::string& name);

// A split file: split name -> sessions. Throws DatasetError naming the file,
// or a session listed in two splits.
std::map<std::string, std::vector<std::string>> load_split(const std::string& path);

// The sessions the split file at `path` lists under `split`, each checked to
// be in the dataset at `dataset_root` (whose dataset.json, if any, must be
// one this build reads). Throws DatasetError naming the file
// and the split it lacks (with those it has) or the session the dataset lacks.
std::vector<std::string> split_sessions(const std::string& path, const std::string& split,
                                        const std::string& dataset_root);

}  // namespace ivoa::dataset
