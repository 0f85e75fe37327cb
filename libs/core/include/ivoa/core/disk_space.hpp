#pragma once
// Free space on the disk a recording goes to, for the processes that write
// for hours (the logger, the Kinect driver's .oni recording).
#include <cstdint>
#include <optional>
#include <string>

namespace ivoa {

// Free bytes on the file system holding `file`'s folder ("." when it names
// none), as this process may use them: root may also fill the blocks a file
// system keeps back for it. Nothing when they cannot be read.
std::optional<uint64_t> free_bytes_for(const std::string& file);

}  // namespace ivoa
