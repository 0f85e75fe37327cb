#include "model_file.hpp"

#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <vector>
#include <cmath>
#include <cstring>

#include <torch/script.h>
#include <unzip.h>
#include <yaml-cpp/yaml.h>

#include "ivoa/core/atomic_files.hpp"
#include "ivoa/core/image_convert.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/core/process.hpp"

namespace ivoa::introspection {
namespace {

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream buf;
  buf << in.rdbuf();
  std::ostringstream hex;
  hex << std::hex << std::hash<std::string>{}(buf.str());
  return hex.str().substr(0, 12);
}

torch::Tensor to_bytes(const std::string& s) {
  auto t = torch::empty({static_cast<int64_t>(s.size())}, torch::kUInt8);
  std::memcpy(t.data_ptr<uint8_t>(), s.data(), s.size());
  return t;
}

std::string from_bytes(const torch::Tensor& t) {
  const auto c = t.to(torch::kCPU).contiguous();
  return std::string(reinterpret_cast<const char*>(c.data_ptr<uint8_t>()), static_cast<size_t>(c.numel()));
}

// A number in JSON's grammar, true, false or null ("nan", which an ostream
// writes for a NaN, is none of them, nor are "+5" or ".5").
bool is_json_literal(const std::string& s) {
  static const std::regex number(R"(-?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?)");
  return s == "true" || s == "false" || s == "null" || std::regex_match(s, number);
}

// A node read from JSON, written back as JSON: quoted strings stay strings,
// numbers and true/false/null stay bare (yaml-cpp's emitter quoted them
// all, so a model re-saved by --calibrate-only said "steps": "14000").
std::string json_of(const YAML::Node& node) {
  std::string json;
  switch (node.Type()) {
    case YAML::NodeType::Map:
      for (const auto& kv : node)
        json += (json.empty() ? "{" : ", ") + json_quote(kv.first.as<std::string>()) + ": " + json_of(kv.second);
      return json.empty() ? "{}" : json + "}";
    case YAML::NodeType::Sequence:
      for (const auto& item : node) json += (json.empty() ? "[" : ", ") + json_of(item);
      return json.empty() ? "[]" : json + "]";
    case YAML::NodeType::Scalar:  // tag "!": it was quoted
      return node.Tag() != "!" && is_json_literal(node.Scalar()) ? node.Scalar() : json_quote(node.Scalar());
    default: return "null";
  }
}

// Absent in models written before sizes were recorded: none. A size past
// any camera's is refused: the live process warms up at the first one.
std::vector<cv::Size> image_sizes_from(const YAML::Node& node, const std::string& where) {
  std::vector<cv::Size> sizes;
  if (!node || node.IsNull()) return sizes;
  const std::string expected = where + ": image_sizes must be a list of [width, height] pairs of positive pixels, " +
                               "e.g. [[960, 600]], each at most " + std::to_string(kMaxImagePixels) + " pixels";
  if (!node.IsSequence()) throw ModelError(expected);
  for (const auto& size : node) {
    std::vector<int> wh;
    try {
      wh = size.as<std::vector<int>>();
    } catch (const YAML::Exception&) {
      throw ModelError(expected + ", not " + json_of(size));
    }
    if (wh.size() != 2 || wh[0] <= 0 || wh[1] <= 0 || int64_t{wh[0]} * wh[1] > kMaxImagePixels)
      throw ModelError(expected + ", not " + json_of(size));
    sizes.emplace_back(wh[0], wh[1]);
  }
  return sizes;
}

}  // namespace

// Reads every entry of a model file (a zip archive) through minizip, which
// checks each one's CRC-32: LibTorch's reader does not (PyTorch builds
// miniz without those checks), so a damaged weight would load as another
// number and the model would predict nonsense without a word. A file that
// is no zip archive is left to LibTorch, which says what it is not.
void check_model_archive(const std::string& path) {
  if (const std::string why = why_not_a_file(path); !why.empty())
    throw ModelError(path + (why == "no such file" ? ": no such model file" : ": " + why));
  const unzFile zip = unzOpen64(path.c_str());
  if (!zip) return;
  std::vector<char> buffer(1 << 16);
  std::string damaged;
  int rc = unzGoToFirstFile(zip);
  for (; rc == UNZ_OK && damaged.empty(); rc = unzGoToNextFile(zip)) {
    char name[512] = {0};
    unzGetCurrentFileInfo64(zip, nullptr, name, sizeof(name) - 1, nullptr, 0, nullptr, 0);
    int read = unzOpenCurrentFile(zip);
    while (read >= 0 && (read = unzReadCurrentFile(zip, buffer.data(), static_cast<unsigned>(buffer.size()))) > 0) {
    }
    const int closed = unzCloseCurrentFile(zip);
    if (read < 0 || closed != UNZ_OK)
      damaged = std::string(name) + (closed == UNZ_CRCERROR ? " fails its CRC-32 check" : " cannot be read");
  }
  unzClose(zip);
  if (damaged.empty() && rc != UNZ_END_OF_LIST_OF_FILE) damaged = "its list of entries cannot be read";
  if (!damaged.empty())
    throw ModelError(path + ": " + damaged + ": the model file is damaged (copy or download it again)");
}

std::string info_to_json(const ModelInfo& i) {
  std::ostringstream o;
  o.precision(8);
  o << "{\"format\": " << json_quote(kFormat) << ", \"version\": 1, \"architecture\": " << json_quote(i.architecture)
    << ", \"detector\": " << json_quote(i.detector) << ", \"patch_size\": " << i.patch_size
    << ", \"stride\": " << i.stride << ", \"input_size\": " << i.input_size << ", \"views\": " << i.views
    << ", \"patch_scale\": " << i.patch_scale << ", \"image_sizes\": " << image_sizes_json(i.image_sizes)
    << ", \"dropout\": " << i.dropout << ", \"color\": \"RGB\""
    << ", \"mean\": [" << i.mean[0] << ", " << i.mean[1] << ", " << i.mean[2] << "], \"std\": [" << i.std[0] << ", "
    << i.std[1] << ", " << i.std[2] << "], \"classes\": [";
  for (size_t k = 0; k < i.classes.size(); ++k) o << (k ? ", " : "") << json_quote(i.classes[k]);
  o << "], \"uncertainty_threshold\": " << i.uncertainty_threshold
    << ", \"verdict_uncertainty_threshold\": " << i.verdict_uncertainty_threshold
    << ", \"training\": " << (i.training_summary.empty() ? "{}" : i.training_summary) << "}";
  return o.str();
}

ModelInfo info_from_json(const std::string& json, const std::string& where) {
  ModelInfo i;
  try {
    const YAML::Node n = YAML::Load(json);
    if (!n["format"] || n["format"].as<std::string>() != kFormat)
      throw ModelError(where + ": metadata is not '" + kFormat + "'");
    i.architecture = n["architecture"].as<std::string>();
    i.detector = n["detector"].as<std::string>("");
    i.patch_size = n["patch_size"].as<int>();
    i.stride = n["stride"].as<int>();
    i.input_size = n["input_size"].as<int>();
    i.views = n["views"].as<int>(1);                   // models written before views existed see the left image only
    i.patch_scale = n["patch_scale"].as<double>(0.0);  // models written before scaling existed: fixed patches
    i.image_sizes = image_sizes_from(n["image_sizes"], where);
    i.dropout = n["dropout"].as<double>();
    for (int c = 0; c < 3; ++c) {
      i.mean[static_cast<size_t>(c)] = n["mean"][c].as<float>();
      i.std[static_cast<size_t>(c)] = n["std"][c].as<float>();
    }
    i.classes = n["classes"].as<std::vector<std::string>>();
    // Absent in older models (a default, none); present, it must read as a number.
    if (n["uncertainty_threshold"]) i.uncertainty_threshold = n["uncertainty_threshold"].as<double>();
    i.verdict_uncertainty_threshold =
        n["verdict_uncertainty_threshold"] ? n["verdict_uncertainty_threshold"].as<double>() : -1.0;
    if (n["training"]) i.training_summary = json_of(n["training"]);
  } catch (const YAML::Exception& e) {
    throw ModelError(where + ": malformed model metadata: " + e.what());
  }
  const std::vector<std::string> expected{kLabelNames.begin(), kLabelNames.end()};
  if (i.classes != expected) throw ModelError(where + ": the model's classes are not TP, TN, FP, FN in that order");
  if (i.patch_size <= 0 || i.stride <= 0 || i.input_size <= 0 || !(i.dropout > 0 && i.dropout < 1))
    throw ModelError(where + ": patch_size, stride, input_size must be positive and dropout in (0, 1)");
  if (i.views != 1 && i.views != 2) throw ModelError(where + ": views must be 1 or 2, not " + std::to_string(i.views));
  if (!(i.patch_scale >= 0)) throw ModelError(where + ": patch_scale must be >= 0");
  if (!std::isfinite(i.uncertainty_threshold) || !std::isfinite(i.verdict_uncertainty_threshold))
    throw ModelError(where + ": its uncertainty gates are not numbers (a training that diverged?)");
  for (size_t c = 0; c < 3; ++c)  // the input normalisation: a std of 0 or a NaN mean made every prediction NaN
    if (!std::isfinite(i.mean[c]) || !std::isfinite(i.std[c]) || !(i.std[c] > 0))
      throw ModelError(where + ": its input normalisation (mean, std) must be finite numbers with std > 0");
  return i;
}

// Serialised in memory first: LibTorch's file writer finishes the archive in
// its destructor, where a full disk aborts the process instead of throwing.
std::string model_bytes(IntrospectionNetImpl& net, const ModelInfo& info) {
  torch::serialize::OutputArchive archive;
  net.save(archive);
  archive.write(kMetadataKey, to_bytes(info_to_json(info)), /*is_buffer=*/true);
  std::ostringstream bytes;
  archive.save_to(bytes);
  return bytes.str();
}

void save_model(IntrospectionNetImpl& net, const ModelInfo& info, const std::string& path) {
  std::string error;
  if (!replace_file(path, model_bytes(net, info), error)) throw std::runtime_error(error);
}

bool read_metadata(const std::string& path, std::string& json) {
  torch::serialize::InputArchive archive;
  archive.load_from(path);
  torch::Tensor t;
  if (!archive.try_read(kMetadataKey, t, /*is_buffer=*/true)) return false;
  json = from_bytes(t);
  return true;
}

NativeModel load_native_model(const std::string& path) {
  check_model_archive(path);
  return load_checked_native_model(path);
}

NativeModel load_checked_native_model(const std::string& path) {
  std::string json;
  try {
    if (!read_metadata(path, json))
      throw ModelError(path + ": not an IVOA model (no '" + std::string(kMetadataKey) + "' metadata)");
  } catch (const c10::Error& e) {
    throw ModelError(path + ": not a LibTorch/TorchScript file (" + std::string(e.what_without_backtrace()) + ")");
  }
  NativeModel m;
  m.info = info_from_json(json, path);
  try {
    m.net = make_network(m.info.architecture, m.info.dropout, m.info.views);
  } catch (const std::invalid_argument& e) {
    throw ModelError(path + ": " + e.what());
  }
  if (m.info.input_size != input_size_of(m.info.architecture))
    throw ModelError(path + ": input_size " + std::to_string(m.info.input_size) + " does not fit architecture " +
                     m.info.architecture);
  try {
    torch::serialize::InputArchive archive;
    archive.load_from(path);
    m.net->load(archive);
  } catch (const c10::Error& e) {
    throw ModelError(path + ": parameters do not fit architecture '" + m.info.architecture +
                     "': " + std::string(e.what_without_backtrace()).substr(0, 300));
  }
  for (const auto& p : m.net->named_parameters())
    if (!torch::isfinite(p.value()).all().item<bool>())
      throw ModelError(path + ": parameter " + p.key() + " holds NaN or infinite weights (a training that diverged?)");
  m.info.id = std::filesystem::path(path).filename().string() + "#" + file_hash(path);
  m.net->eval();
  return m;
}

}  // namespace ivoa::introspection
