#pragma once
#include <functional>
#include <optional>
#include <string>

namespace ivoa {

// `path` with "-n" before its extension: ("logs/clip.oni", 2) gives
// "logs/clip-2.oni"; n = 0 gives `path` itself.
std::string numbered_file_name(const std::string& path, int n);

// The first of path, path-1, ..., path-max_suffix that `take` accepts;
// `take` returns false for a name already in use (and may create the file
// to claim it). nullopt when all are in use. Lets a respawned recorder
// start a new file instead of overwriting, or refusing, the last one.
std::optional<std::string> first_free_numbered_name(const std::string& path, int max_suffix,
                                                    const std::function<bool(const std::string&)>& take);

}  // namespace ivoa
