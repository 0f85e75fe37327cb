#include "ivoa/dataset/dataset_format.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/file_lock.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/process.hpp"

namespace fs = std::filesystem;

namespace ivoa::dataset {
namespace {

constexpr int kMaxPatchSize = 4096;      // px a side; patches are 100 px
constexpr int kDatasetIndexVersion = 1;  // dataset.json's "version": what this build writes and reads
constexpr int kMaxEvidenceSize = 4096;   // values per sample; JPP-C keeps one per ground sample, a few dozen

constexpr const char* kSamplesHeaderV1 =
    "sample,frame,utime,depth_utime,cell,label,stereo_state,depth_state,x,y,u,v,phenomena,phenomenon,surface";
constexpr const char* kSamplesHeader =
    "sample,frame,utime,depth_utime,cell,label,stereo_state,depth_state,x,y,u,v,phenomena,phenomenon,surface,"
    "patch_side";

std::string session_json(const SessionInfo& i) {
  std::ostringstream o;
  o.precision(10);
  o << "{\n  \"session\": " << json_quote(i.session) << ",\n  \"detector\": " << json_quote(i.detector)
    << ",\n  \"labels_from\": " << json_quote(i.labels_from) << ",\n  \"logs\": [";
  for (size_t k = 0; k < i.logs.size(); ++k) o << (k ? ", " : "") << json_quote(i.logs[k]);
  o << "],\n  \"scene\": " << json_quote(i.scene) << ",\n  \"seed\": " << i.seed
    << ",\n  \"environment\": " << json_quote(i.environment) << ",\n  \"rig_name\": " << json_quote(i.rig_name)
    << ",\n  \"image_size\": [" << i.image_size.width << ", " << i.image_size.height << "]"
    << ",\n  \"patch_size\": " << i.patch_size << ",\n  \"views\": " << i.views
    << ",\n  \"patch_scale\": " << i.patch_scale << ",\n  \"tn_kept\": " << i.tn_kept
    << ",\n  \"evidence_size\": " << i.evidence_size << ",\n  \"tn_dropped\": " << i.tn_dropped
    << ",\n  \"frames\": " << i.frames << ",\n  \"samples\": " << i.samples << ",\n  \"class_counts\": {";
  for (int c = 0; c < kNumClasses; ++c) o << (c ? ", " : "") << json_quote(kLabelNames[c]) << ": " << i.class_counts[c];
  const QueryGridConfig& g = i.grid;
  o << "},\n  \"grid\": {\"x_min\": " << g.x_min << ", \"x_max\": " << g.x_max << ", \"y_min\": " << g.y_min
    << ", \"y_max\": " << g.y_max << ", \"spacing\": " << g.spacing << ", \"safety_radius\": " << g.safety_radius
    << ", \"patch_size\": " << g.patch_size << "}\n}\n";
  return o.str();
}

template <class T>
T get(const YAML::Node& node, const std::string& key, const std::string& where) {
  if (!node[key]) throw DatasetError(where + ": missing key '" + key + "'");
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception& e) {
    throw DatasetError(where + ": key '" + key + "': " + e.what());
  }
}

// session.json's image_size: [width, height] of the left images, [0, 0]
// where not known, no larger than any camera's.
cv::Size image_size_from(const YAML::Node& root, const std::string& where) {
  const std::string expected = where + ": image_size must be [width, height] in pixels ([0, 0]: not known), at most " +
                               std::to_string(kMaxImagePixels) + " pixels";
  std::vector<int> wh;
  try {
    wh = root["image_size"].as<std::vector<int>>();
  } catch (const YAML::Exception&) {
    throw DatasetError(expected);
  }
  if (wh.size() != 2 || wh[0] < 0 || wh[1] < 0 || (wh[0] == 0) != (wh[1] == 0) ||
      int64_t{wh[0]} * wh[1] > kMaxImagePixels)
    throw DatasetError(expected);
  return cv::Size(wh[0], wh[1]);
}

// A dataset file that is missing or no file (a folder in its place gave
// "basic_filebuf::underflow ... Is a directory"; a named pipe blocked the
// reader for ever) is named as such.
void require_file(const std::string& path) {
  if (const std::string why = why_not_a_file(path); !why.empty()) throw DatasetError(path + ": " + why);
}

// A key given twice in `node` or any map within it is refused: yaml-cpp
// reads the first, Python's json (the report) the last. `what` names a
// top-level key; nested ones are named by their path ("grid.patch_size").
void refuse_repeated_keys(const YAML::Node& node, const std::string& path, const std::string& what,
                          const std::string& prefix = "") {
  if (node.IsSequence())
    for (const auto& item : node) refuse_repeated_keys(item, path, what, prefix);
  if (!node.IsMap()) return;
  std::set<std::string> keys;
  for (const auto& entry : node) {
    if (!entry.first.IsScalar()) continue;
    const std::string name = prefix + entry.first.Scalar();
    if (!keys.insert(entry.first.Scalar()).second)
      throw DatasetError(path + ": " + (prefix.empty() ? what : "key") + " '" + name + "' is given twice");
    refuse_repeated_keys(entry.second, path, what, name + ".");
  }
}

// A YAML (JSON) file read whole, no key given twice at any level.
YAML::Node load_yaml_file(const std::string& path, const std::string& what = "key") {
  require_file(path);
  YAML::Node root = YAML::LoadFile(path);
  refuse_repeated_keys(root, path, what);
  return root;
}

SessionInfo parse_session_json(const std::string& path) {
  YAML::Node root;
  try {
    root = load_yaml_file(path);
  } catch (const YAML::Exception& e) {
    throw DatasetError(path + ": cannot read session metadata: " + e.what());
  }
  SessionInfo i;
  i.session = get<std::string>(root, "session", path);
  i.detector = get<std::string>(root, "detector", path);
  i.labels_from = get<std::string>(root, "labels_from", path);
  i.logs = get<std::vector<std::string>>(root, "logs", path);
  i.scene = get<std::string>(root, "scene", path);
  i.seed = get<int64_t>(root, "seed", path);
  i.environment = get<std::string>(root, "environment", path);
  i.rig_name = get<std::string>(root, "rig_name", path);
  if (root["image_size"]) i.image_size = image_size_from(root, path);  // written before it was recorded: 0 x 0
  i.patch_size = get<int>(root, "patch_size", path);
  // the bound keeps patches.bin's expected size from overflowing (a huge
  // patch_size made an empty file pass its size check)
  if (i.patch_size <= 0 || i.patch_size > kMaxPatchSize)
    throw DatasetError(path + ": patch_size must be 1 to " + std::to_string(kMaxPatchSize) + ", not " +
                       std::to_string(i.patch_size));
  i.views = root["views"] ? get<int>(root, "views", path) : 1;  // datasets written before views existed
  if (i.views != 1 && i.views != 2) throw DatasetError(path + ": views must be 1 or 2, not " + std::to_string(i.views));
  i.patch_scale = root["patch_scale"] ? get<double>(root, "patch_scale", path) : 0.0;  // written before scaling existed
  if (i.patch_scale < 0) throw DatasetError(path + ": patch_scale must be >= 0");
  i.tn_kept = root["tn_kept"] ? get<double>(root, "tn_kept", path) : 1.0;  // written before TN could be thinned
  if (!(i.tn_kept > 0 && i.tn_kept <= 1)) throw DatasetError(path + ": tn_kept must be in (0, 1]");
  i.evidence_size = root["evidence_size"] ? get<int>(root, "evidence_size", path) : 0;  // written before evidence
  if (i.evidence_size < 0 || i.evidence_size > kMaxEvidenceSize)
    throw DatasetError(path + ": evidence_size must be 0 to " + std::to_string(kMaxEvidenceSize) + ", not " +
                       std::to_string(i.evidence_size));
  i.tn_dropped = root["tn_dropped"] ? get<int64_t>(root, "tn_dropped", path) : 0;
  i.frames = get<int64_t>(root, "frames", path);
  i.samples = get<int64_t>(root, "samples", path);
  if (i.frames < 0 || i.samples < 0) throw DatasetError(path + ": frames and samples must be >= 0");
  const YAML::Node counts = root["class_counts"];
  for (int c = 0; c < kNumClasses; ++c) i.class_counts[c] = get<int64_t>(counts, kLabelNames[c], path);
  const YAML::Node g = root["grid"];
  i.grid.x_min = get<double>(g, "x_min", path);
  i.grid.x_max = get<double>(g, "x_max", path);
  i.grid.y_min = get<double>(g, "y_min", path);
  i.grid.y_max = get<double>(g, "y_max", path);
  i.grid.spacing = get<double>(g, "spacing", path);
  i.grid.safety_radius = get<double>(g, "safety_radius", path);
  i.grid.patch_size = get<int>(g, "patch_size", path);
  return i;
}

// The name of samples.csv's column `index` (0-based).
std::string sample_column(int index) {
  std::istringstream header(kSamplesHeader);
  std::string name;
  for (int k = 0; k <= index && std::getline(header, name, ','); ++k) {
  }
  return name;
}

// A coordinate that is not finite would travel into every figure and metric by distance.
void check_finite(const SampleRecord& s, const std::string& where) {
  const std::pair<const char*, float> coordinates[] = {{"x", s.x}, {"y", s.y}, {"u", s.u}, {"v", s.v}};
  for (const auto& [name, value] : coordinates)
    if (!std::isfinite(value)) throw DatasetError(where + ": column " + name + " is " + std::to_string(value));
}

// A cell's pixel off the image (where the size is known: not 0 x 0) cuts no
// patch there and would draw its ring and dot off every overlay.
void check_in_image(const SampleRecord& s, const cv::Size& image, const std::string& where) {
  if (image.empty() || (s.u >= 0 && s.u < image.width && s.v >= 0 && s.v < image.height)) return;
  throw DatasetError(fmt::format("{}: pixel (u {}, v {}) lies off the {} x {} image (session.json)", where, s.u, s.v,
                                 image.width, image.height));
}

// Whole-field numbers: "16abc" or "" is not a number (sscanf took "16").
bool parse_field(std::string_view field, long long& out) {
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), out);
  return error == std::errc() && end == field.data() + field.size();
}
bool parse_field(std::string_view field, int& out) {
  long long wide = 0;
  if (!parse_field(field, wide) || wide < INT_MIN || wide > INT_MAX) return false;
  out = static_cast<int>(wide);
  return true;
}
bool parse_field(std::string_view field, float& out) {
  const std::string text(field);
  char* end = nullptr;
  out = std::strtof(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

// `columns`: 15 (before patch_side was recorded) or 16.
// `index`: the row's place among the samples (0-based), its sample number.
SampleRecord parse_sample_row(const std::string& line, int columns, int64_t index, const std::string& where) {
  std::vector<std::string_view> fields;
  for (size_t start = 0;;) {
    const size_t comma = line.find(',', start);
    fields.emplace_back(line.data() + start, (comma == std::string::npos ? line.size() : comma) - start);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (static_cast<int>(fields.size()) != columns)
    throw DatasetError(where + ": " + std::to_string(fields.size()) + " fields, the header has " +
                       std::to_string(columns));
  SampleRecord s;
  long long sample = 0, frame = 0, utime = 0, depth_utime = 0;
  const bool ok[] = {parse_field(fields[0], sample),
                     parse_field(fields[1], frame),
                     parse_field(fields[2], utime),
                     parse_field(fields[3], depth_utime),
                     parse_field(fields[4], s.cell),
                     parse_field(fields[5], s.label),
                     parse_field(fields[6], s.stereo_state),
                     parse_field(fields[7], s.depth_state),
                     parse_field(fields[8], s.x),
                     parse_field(fields[9], s.y),
                     parse_field(fields[10], s.u),
                     parse_field(fields[11], s.v),
                     parse_field(fields[12], s.phenomena),
                     parse_field(fields[13], s.phenomenon),
                     parse_field(fields[14], s.surface),
                     columns < 16 || parse_field(fields[15], s.patch_side)};
  for (int k = 0; k < columns; ++k)
    if (!ok[k])
      throw DatasetError(where + ": column " + sample_column(k) + " (" + std::to_string(k + 1) + " of " +
                         std::to_string(columns) + ") is missing or not a number in '" + line + "'");
  check_finite(s, where);
  if (s.label < 0 || s.label >= kNumClasses)
    throw DatasetError(where + ": label " + std::to_string(s.label) + " out of range");
  if (sample != index)
    throw DatasetError(where + ": sample " + std::to_string(sample) + " where sample " + std::to_string(index) +
                       " is due (rows reordered, cut or added?)");
  s.frame = frame;
  s.utime = utime;
  s.depth_utime = depth_utime;
  return s;
}

}  // namespace

struct SessionWriter::Files {
  std::FILE* patches = nullptr;
  std::FILE* samples = nullptr;
  std::FILE* evidence = nullptr;  // only if evidence_size > 0
  ~Files() {
    for (std::FILE* f : {patches, samples, evidence})
      if (f) std::fclose(f);
  }
};

namespace {

// A folder the new session will replace must be a session built before:
// session.json and only the files a session holds. Anything else (a log
// kept there, notes) would be deleted with it.
void check_replaceable(const std::string& dir, const std::string& name) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  static const std::set<std::string> kSessionFiles = {"session.json", "samples.csv", "patches.bin", "evidence.f32",
                                                      "frames.csv"};
  const auto refuse = [&](const std::string& why) {
    throw DatasetError("session name '" + name + "': " + dir + " " + why +
                       ", so it is not replaced (a new session replaces only one built before); name another "
                       "session or move it");
  };
  if (!fs::exists(dir + "/session.json")) refuse("is a folder without session.json, not a dataset session");
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (!kSessionFiles.count(entry.path().filename().string()))
      refuse("holds " + entry.path().filename().string() + ", which is not a session's");
}

}  // namespace

void check_session_name(const std::string& name) {
  // "..": the session's files would land beside the dataset
  if (name.empty() || name[0] == '.' || name.find('/') != std::string::npos)
    throw DatasetError("session name '" + name +
                       "' must be a folder name (not empty, no '/', not starting with '.': the builder's own folders "
                       "do)");
  // Written unquoted into predictions.csv and causes.csv, a comma shifted
  // every field after it and the report refused the file.
  for (const char c : name)
    if (c == ',' || c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw DatasetError("session name '" + name +
                         "' has a comma, a quote or a control character, which the CSV files that name it "
                         "cannot hold unquoted: rename the log or give --session");
}

SessionWriter::SessionWriter(const std::string& dataset_root, SessionInfo info)
    : dir_((fs::path(dataset_root) / info.session).string()),
      work_dir_((fs::path(dataset_root) / ("." + info.session + ".partial")).string()),
      info_(std::move(info)),
      files_(std::make_unique<Files>()) {
  const std::string& name = info_.session;
  check_session_name(name);
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw DatasetError("session name '" + name + "': " + dir_ + " is a file, not a session folder; name another");
  check_replaceable(dir_, name);
  fs::remove_all(work_dir_, ec);  // left by a build that was killed
  fs::create_directories(work_dir_, ec);
  if (ec) throw DatasetError(work_dir_ + ": cannot create the session's folder: " + ec.message());
  files_->patches = std::fopen((work_dir_ + "/patches.bin").c_str(), "wb");
  files_->samples = std::fopen((work_dir_ + "/samples.csv").c_str(), "w");
  if (info_.evidence_size > 0) files_->evidence = std::fopen((work_dir_ + "/evidence.f32").c_str(), "wb");
  if (!files_->patches || !files_->samples || (info_.evidence_size > 0 && !files_->evidence))
    throw DatasetError(dir_ + ": cannot write session files");
  std::fprintf(files_->samples, "%s\n", kSamplesHeader);
  info_.frames = info_.samples = info_.tn_dropped = 0;
  info_.class_counts = {};
}

SessionWriter::~SessionWriter() {
  try {
    close();
  } catch (...) {
  }
}

int64_t SessionWriter::add_frame(int64_t utime, int64_t depth_utime, int32_t cells_labelled) {
  frames_.push_back({utime, depth_utime, cells_labelled, 0});
  return static_cast<int64_t>(frames_.size()) - 1;
}

void SessionWriter::add_sample(SampleRecord s, const cv::Mat& patch, const std::vector<float>& evidence) {
  const int p = info_.patch_size;
  if (!files_->patches) throw DatasetError(dir_ + ": session already closed");
  if (patch.rows != p * info_.views || patch.cols != p || patch.type() != CV_8UC3)
    throw DatasetError("patch must be " + std::to_string(p * info_.views) + "x" + std::to_string(p) + " 8-bit BGR (" +
                       std::to_string(info_.views) + " view(s) of " + std::to_string(p) + " px)");
  if (s.label < 0 || s.label >= kNumClasses)
    throw DatasetError("sample label " + std::to_string(s.label) + " out of range");
  if (s.frame < 0 || s.frame >= static_cast<int64_t>(frames_.size())) throw DatasetError("sample refers to no frame");
  check_finite(s, dir_ + " sample " + std::to_string(info_.samples));  // what SessionReader would refuse
  check_in_image(s, info_.image_size, dir_ + " sample " + std::to_string(info_.samples));
  if (static_cast<int>(evidence.size()) != info_.evidence_size)
    throw DatasetError(fmt::format("sample {}: {} evidence values, the session stores {}", info_.samples,
                                   evidence.size(), info_.evidence_size));
  write_evidence(evidence);
  const cv::Mat contiguous = patch.isContinuous() ? patch : patch.clone();
  const size_t bytes = static_cast<size_t>(p) * p * 3 * info_.views;
  if (std::fwrite(contiguous.data, 1, bytes, files_->patches) != bytes)
    throw DatasetError(dir_ + "/patches.bin: write failed (disk full?)");
  if (s.patch_side == 0) s.patch_side = p;
  std::fprintf(files_->samples, "%lld,%lld,%lld,%lld,%d,%d,%d,%d,%.4f,%.4f,%.2f,%.2f,%d,%d,%d,%d\n",
               static_cast<long long>(info_.samples), static_cast<long long>(s.frame), static_cast<long long>(s.utime),
               static_cast<long long>(s.depth_utime), s.cell, s.label, s.stereo_state, s.depth_state, s.x, s.y, s.u,
               s.v, s.phenomena, s.phenomenon, s.surface, s.patch_side);
  ++info_.samples;
  ++info_.class_counts[static_cast<size_t>(s.label)];
  ++frames_[static_cast<size_t>(s.frame)].samples;
}

void SessionWriter::write_evidence(const std::vector<float>& evidence) {
  if (evidence.empty()) return;
  if (std::fwrite(evidence.data(), sizeof(float), evidence.size(), files_->evidence) != evidence.size())
    throw DatasetError(dir_ + "/evidence.f32: write failed (disk full?)");
}

void SessionWriter::abandon() {
  for (std::FILE* f : {files_->patches, files_->samples, files_->evidence})
    if (f) std::fclose(f);
  files_->patches = files_->samples = files_->evidence = nullptr;
  if (keep_work_dir_) return;
  std::error_code ec;
  fs::remove_all(work_dir_, ec);  // nothing there once close() has put the session in place
}

// The finished session takes the place of any folder of that name: moved
// aside to .NAME.replaced, the new one renamed in (the old one back if that
// fails), the old one removed. Where a step fails, the error says where
// both sessions are.
void SessionWriter::replace_session_folder() {
  const std::string aside = (fs::path(dir_).parent_path() / ("." + info_.session + ".replaced")).string();
  std::error_code ec;
  fs::remove_all(aside, ec);  // left by a build killed between the renames below
  if (ec) throw DatasetError(aside + ": cannot remove what an earlier build left (" + ec.message() + ")");
  const bool had_one = fs::exists(dir_);
  if (had_one) fs::rename(dir_, aside, ec);
  if (ec) throw DatasetError(dir_ + ": cannot move the session built before aside (" + ec.message() + ")");
  fs::rename(work_dir_, dir_, ec);
  if (ec) {
    keep_work_dir_ = true;
    std::error_code restored;
    if (had_one) fs::rename(aside, dir_, restored);
    throw DatasetError(dir_ + ": cannot put the built session in place (" + ec.message() + "); it is in " + work_dir_ +
                       (restored ? ", and the one built before is in " + aside : ""));
  }
  fs::remove_all(aside, ec);
}

void SessionWriter::close() {
  if (!files_->patches) return;
  bool ok = std::fflush(files_->patches) == 0 && std::fflush(files_->samples) == 0;
  if (files_->evidence) ok = std::fclose(files_->evidence) == 0 && ok;
  std::fclose(files_->patches);
  std::fclose(files_->samples);
  files_->patches = files_->samples = files_->evidence = nullptr;
  if (!ok) throw DatasetError(dir_ + ": write failed (disk full?)");
  info_.frames = static_cast<int64_t>(frames_.size());
  std::ofstream frames(work_dir_ + "/frames.csv");
  frames << "frame,utime,depth_utime,cells_labelled,samples\n";
  for (size_t k = 0; k < frames_.size(); ++k)
    frames << k << "," << frames_[k].utime << "," << frames_[k].depth_utime << "," << frames_[k].cells_labelled << ","
           << frames_[k].samples << "\n";
  std::ofstream json(work_dir_ + "/session.json");
  json << session_json(info_);
  if (!frames.flush() || !json.flush()) throw DatasetError(dir_ + ": write failed (disk full?)");
  frames.close(), json.close();
  replace_session_folder();
  register_session(fs::path(dir_).parent_path().string(), info_.session, info_.patch_size);
}

SessionReader::SessionReader(const std::string& session_dir) : dir_(session_dir) {
  info_ = parse_session_json(dir_ + "/session.json");
  // Splits and predictions name sessions by folder; a renamed folder would
  // be evaluated under one name and looked up under the other.
  fs::path folder = fs::path(dir_).lexically_normal();
  if (folder.filename().empty()) folder = folder.parent_path();
  if (folder.filename() != info_.session && folder.filename() != ".")
    throw DatasetError(dir_ + "/session.json: names the session '" + info_.session + "' but its folder is '" +
                       folder.filename().string() + "': rename the folder back, or build the session again");
  require_file(dir_ + "/samples.csv");
  std::ifstream in(dir_ + "/samples.csv");
  if (!in) throw DatasetError(dir_ + "/samples.csv: cannot open");
  std::string line;
  std::getline(in, line);
  const bool has_side = line == kSamplesHeader;
  if (!line.empty() && line.back() == '\r')
    throw DatasetError(dir_ + "/samples.csv: Windows line ends (CR LF); the builder writes LF only");
  if (!has_side && line != kSamplesHeaderV1)
    throw DatasetError(dir_ + "/samples.csv: unexpected header '" + line + "' (expected '" + kSamplesHeader + "')");
  size_t row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    const std::string where = dir_ + "/samples.csv line " + std::to_string(row);
    SampleRecord s = parse_sample_row(line, has_side ? 16 : 15, static_cast<int64_t>(samples_.size()), where);
    if (s.frame < 0 || s.frame >= info_.frames)
      throw DatasetError(where + ": frame " + std::to_string(s.frame) + ", but the session has " +
                         std::to_string(info_.frames) + " frames (session.json)");
    check_in_image(s, info_.image_size, where);
    if (!has_side) s.patch_side = info_.patch_size;
    samples_.push_back(s);
  }
  check_index_matches_metadata();
  const size_t patch_bytes = this->patch_bytes();
  const std::string patches = dir_ + "/patches.bin";
  require_file(patches);
  const int fd = ::open(patches.c_str(), O_RDONLY);
  if (fd < 0) throw DatasetError(patches + ": cannot open");
  struct stat st {};
  fstat(fd, &st);
  mapped_bytes_ = static_cast<size_t>(st.st_size);
  if (mapped_bytes_ != samples_.size() * patch_bytes) {
    ::close(fd);
    throw DatasetError(patches + ": " + std::to_string(mapped_bytes_) + " bytes, " +
                       (mapped_bytes_ % patch_bytes == 0
                            ? std::to_string(mapped_bytes_ / patch_bytes) + " patches"
                            : "not a whole number of " + std::to_string(patch_bytes) + "-byte patches") +
                       "; samples.csv lists " + std::to_string(samples_.size()) + " (truncated or damaged dataset?)");
  }
  if (mapped_bytes_ > 0) {
    void* m = mmap(nullptr, mapped_bytes_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (m == MAP_FAILED) {
      ::close(fd);
      throw DatasetError(patches + ": cannot memory-map");
    }
    mapped_ = static_cast<const uint8_t*>(m);
    // Training reads patches in random order: without this hint each page
    // fault reads the device's whole readahead window around it (8 MB on
    // some disks) and a dataset larger than memory trains at disk speed.
    // Readers call prefetch() for what they need next.
    madvise(m, mapped_bytes_, MADV_RANDOM);
  }
  ::close(fd);
  read_evidence();
}

// session.json's counts are what `ivoa-dataset info` and the reports show:
// a session whose index was edited or cut short must not claim other numbers.
void SessionReader::check_index_matches_metadata() const {
  std::array<int64_t, kNumClasses> counts{};
  for (const SampleRecord& s : samples_) ++counts[static_cast<size_t>(s.label)];
  if (static_cast<int64_t>(samples_.size()) == info_.samples && counts == info_.class_counts) return;
  const auto listed = [](int64_t total, const std::array<int64_t, kNumClasses>& c) {
    std::string text = std::to_string(total) + " samples (";
    for (int k = 0; k < kNumClasses; ++k)
      text += fmt::format("{}{} {}", k ? ", " : "", kLabelNames[k], c[static_cast<size_t>(k)]);
    return text + ")";
  };
  throw DatasetError(dir_ + ": session.json says " + listed(info_.samples, info_.class_counts) +
                     ", samples.csv lists " + listed(static_cast<int64_t>(samples_.size()), counts) +
                     " (edited or truncated session?)");
}

void SessionReader::read_evidence() {
  if (info_.evidence_size == 0) return;
  const std::string path = dir_ + "/evidence.f32";
  require_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw DatasetError(path + ": cannot open (session.json says evidence_size " + std::to_string(info_.evidence_size) +
                       ")");
  // The file's size is checked before anything is allocated for it: a 7.7 kB
  // file with a large evidence_size cost 2 GB.
  const uint64_t expected = samples_.size() * static_cast<uint64_t>(info_.evidence_size) * sizeof(float);
  std::error_code error;
  if (fs::file_size(path, error) != expected || error)
    throw DatasetError(path + ": does not hold " + std::to_string(info_.evidence_size) + " values for each of the " +
                       std::to_string(samples_.size()) + " samples (truncated dataset?)");
  evidence_.resize(samples_.size() * static_cast<size_t>(info_.evidence_size));
  in.read(reinterpret_cast<char*>(evidence_.data()), static_cast<std::streamsize>(evidence_.size() * sizeof(float)));
  if (in.gcount() != static_cast<std::streamsize>(evidence_.size() * sizeof(float)) || in.peek() != EOF)
    throw DatasetError(path + ": does not hold " + std::to_string(info_.evidence_size) + " values for each of the " +
                       std::to_string(samples_.size()) + " samples (truncated dataset?)");
  // NaN is "not observed"; an infinity is damage (training blamed --lr for it)
  const auto bad = std::find_if(evidence_.begin(), evidence_.end(), [](float v) { return std::isinf(v); });
  if (bad != evidence_.end())
    throw DatasetError(path + ": sample " + std::to_string((bad - evidence_.begin()) / info_.evidence_size) +
                       " holds an infinite value");
}

const float* SessionReader::evidence(size_t i) const {
  return evidence_.empty() ? nullptr : evidence_.data() + i * static_cast<size_t>(info_.evidence_size);
}

SessionReader::~SessionReader() {
  if (mapped_) munmap(const_cast<uint8_t*>(mapped_), mapped_bytes_);
}

size_t SessionReader::patch_bytes() const {
  return static_cast<size_t>(info_.patch_size) * info_.patch_size * 3 * info_.views;
}

const uint8_t* SessionReader::patch_data(size_t i) const { return mapped_ + i * patch_bytes(); }

void SessionReader::prefetch(size_t first, size_t count) const {
  if (!mapped_ || first >= samples_.size() || count == 0) return;
  count = std::min(count, samples_.size() - first);
  static const auto page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  const size_t begin = first * patch_bytes() / page * page;
  const size_t end = (first + count) * patch_bytes();
  // In pieces: the kernel reads at most its readahead window per call.
  constexpr size_t kPiece = size_t{1} << 20;
  for (size_t at = begin; at < end; at += kPiece)  // a hint; errors change nothing
    madvise(const_cast<uint8_t*>(mapped_) + at, std::min(kPiece, end - at), MADV_WILLNEED);
}

cv::Mat SessionReader::patch(size_t i) const {
  return cv::Mat(info_.patch_size * info_.views, info_.patch_size, CV_8UC3, const_cast<uint8_t*>(patch_data(i)));
}

namespace {

// dataset.json's "format" and "version" (every index this project wrote has both):
// a later version may lay its sessions out otherwise, and reading it as
// this one would give wrong samples rather than an error.
void check_index_format(const YAML::Node& root, const std::string& path) {
  const auto shown = [](const YAML::Node& n) { return n.IsNull() ? std::string("null") : YAML::Dump(n); };  // JSON's
  const YAML::Node format = root["format"], version = root["version"];
  if (format && (!format.IsScalar() || format.Scalar() != "ivoa-dataset"))
    throw DatasetError(path + ": format '" + shown(format) + "', not 'ivoa-dataset': not this project's dataset index");
  if (!version) return;
  long long number = 0;  // wide: any whole number past this build's is a later version; a quoted "1" is text
  if (!version.IsScalar() || version.Tag() == "!" || !YAML::convert<long long>::decode(version, number) || number < 1)
    throw DatasetError(path + ": version '" + shown(version) + "' is not a version number (1, 2, ...)");
  if (number > kDatasetIndexVersion)
    throw DatasetError(path + ": dataset version " + std::to_string(number) + "; this build reads 1 to " +
                       std::to_string(kDatasetIndexVersion) + " (written by a newer ivoa-dataset? use that one)");
}

}  // namespace

std::vector<std::string> list_sessions(const std::string& dataset_root) {
  const std::string path = dataset_root + "/dataset.json";
  if (!fs::exists(path)) return {};
  std::vector<std::string> sessions;
  try {
    const YAML::Node root = load_yaml_file(path);
    const auto not_an_index = [&] {
      return DatasetError(path +
                          ": not a dataset index (an object with a \"sessions\" list; rebuild it with "
                          "ivoa-dataset build)");
    };
    if (!root.IsMap()) throw not_an_index();
    check_index_format(root, path);  // first: a later version may list its sessions otherwise
    if (!root["sessions"] || !root["sessions"].IsSequence()) throw not_an_index();
    sessions = root["sessions"].as<std::vector<std::string>>();
  } catch (const YAML::Exception& e) {
    throw DatasetError(path + ": " + e.what());
  }
  std::set<std::string> seen;  // listed twice, a session's samples were counted twice
  for (const auto& s : sessions)
    if (!seen.insert(s).second) throw DatasetError(path + ": session '" + s + "' is listed twice");
  return sessions;
}

namespace {

// DATASET/.dataset.lock while held: several ivoa-dataset builds may add
// sessions to one dataset at once.
FileLock lock_dataset(const std::string& dataset_root) {
  try {
    return FileLock::wait_for(dataset_root + "/.dataset.lock");
  } catch (const FileLockError& e) {
    throw DatasetError(std::string(e.what()) + " (the dataset's lock)");
  }
}

}  // namespace

void register_session(const std::string& dataset_root, const std::string& session, int patch_size) {
  const FileLock lock = lock_dataset(dataset_root);
  std::vector<std::string> sessions = list_sessions(dataset_root);
  if (std::find(sessions.begin(), sessions.end(), session) == sessions.end()) sessions.push_back(session);
  std::sort(sessions.begin(), sessions.end());
  std::ostringstream out;
  out << "{\n  \"format\": \"ivoa-dataset\",\n  \"version\": " << kDatasetIndexVersion
      << ",\n  \"patch_size\": " << patch_size
      << ",\n  \"label_names\": [\"TP\", \"TN\", \"FP\", \"FN\"],\n  \"sessions\": [";
  for (size_t k = 0; k < sessions.size(); ++k) out << (k ? ", " : "") << json_quote(sessions[k]);
  out << "]\n}\n";
  std::string error;  // replaced whole: a reader never sees half a list
  if (!replace_file(dataset_root + "/dataset.json", out.str(), error))
    throw DatasetError(error + " (the list of sessions)");
}

std::map<std::string, std::vector<std::string>> load_split(const std::string& path) {
  YAML::Node root;
  try {
    root = load_yaml_file(path, "split");
  } catch (const YAML::Exception& e) {
    throw DatasetError(path + ": cannot read split file: " + e.what());
  }
  if (!root.IsMap()) throw DatasetError(path + ": a split file maps split names to lists of sessions");
  std::map<std::string, std::vector<std::string>> splits;
  std::map<std::string, std::string> owner;
  for (const auto& kv : root) {
    const std::string name = kv.first.as<std::string>();
    std::vector<std::string> sessions;
    try {
      sessions = kv.second.as<std::vector<std::string>>();
    } catch (const YAML::Exception&) {
      throw DatasetError(path + ": split '" + name + "' must be a list of session names");
    }
    for (const auto& s : sessions) {
      // A path would reach another folder, or the same session by another name.
      if (s.empty() || s.front() == '.' || s.find('/') != std::string::npos)  // .NAME: a build's work folder
        throw DatasetError(path + ": split '" + name + "': '" + s +
                           "' is not a session name (a folder of the dataset, such as office_s31, not a path)");
      if (owner.count(s))
        throw DatasetError(path + ": session '" + s + "' is in both '" + owner[s] + "' and '" + name + "'");
      owner[s] = name;
    }
    splits[name] = std::move(sessions);
  }
  return splits;
}

std::vector<std::string> split_sessions(const std::string& path, const std::string& split,
                                        const std::string& dataset_root) {
  list_sessions(dataset_root);  // its index checked: another version's sessions may be laid out otherwise
  const auto splits = load_split(path);
  const auto it = splits.find(split);
  if (it == splits.end()) {
    std::string names;
    for (const auto& [name, sessions] : splits) names += (names.empty() ? "" : ", ") + name;
    throw DatasetError(path + ": no split '" + split + "' (it has: " + (names.empty() ? "none" : names) + ")");
  }
  for (const auto& session : it->second) {
    const std::string folder = dataset_root + "/" + session;
    if (fs::is_directory(folder) && !fs::exists(folder + "/session.json"))
      throw DatasetError(folder + "/session.json: missing (split '" + split + "' of " + path +
                         " names the session; a build that did not finish? rebuild it with ivoa-dataset build)");
    if (!fs::exists(folder + "/session.json"))
      throw DatasetError(path + ": split '" + split + "' names session '" + session + "', which is not in " +
                         dataset_root);
  }
  return it->second;
}

}  // namespace ivoa::dataset
