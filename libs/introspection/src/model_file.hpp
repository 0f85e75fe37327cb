#pragma once
// Model files: the network's parameters and buffers (torch::save format,
// which Python's torch.jit.load also reads) plus a JSON metadata blob
// stored as the uint8 buffer "ivoa_metadata" (architecture, patch, stride,
// normalisation, class order, training summary).
#include <memory>
#include <string>

#include "ivoa/introspection/model.hpp"
#include "networks.hpp"

namespace ivoa::introspection {

inline constexpr const char* kMetadataKey = "ivoa_metadata";
inline constexpr const char* kFormat = "ivoa-introspection-model";

std::string info_to_json(const ModelInfo& info);
// Throws ModelError naming `where` for JSON that is not ivoa model metadata.
ModelInfo info_from_json(const std::string& json, const std::string& where);

// The model file's bytes; save_model writes them whole or not at all (a
// failed write keeps the previous file) and throws std::runtime_error naming
// the file and the reason.
std::string model_bytes(IntrospectionNetImpl& net, const ModelInfo& info);
void save_model(IntrospectionNetImpl& net, const ModelInfo& info, const std::string& path);

struct NativeModel {
  std::shared_ptr<IntrospectionNetImpl> net;
  ModelInfo info;
};
// Throws ModelError for a missing file or one that is no file (a named pipe
// would block the reader for ever), and naming the entry if the file is a
// zip archive with an entry that fails its CRC-32 (LibTorch's reader does
// not check them).
void check_model_archive(const std::string& path);

NativeModel load_native_model(const std::string& path);
// load_native_model of a file check_model_archive has just passed, so that
// its CRCs are not checked a second time.
NativeModel load_checked_native_model(const std::string& path);
// The metadata of any model file (native or scripted), if it has one.
bool read_metadata(const std::string& path, std::string& json);

}  // namespace ivoa::introspection
