#pragma once
// The session a log file belongs to, from its name: "run-3.lcmlog.02" ->
// "run-3" (lcm-logger's split files .NN, and the .lcmlog/.lcm/.log
// extensions, dropped). Dataset sessions and the tools that join per-session
// outputs name sessions this way.
#include <string>
#include <vector>

namespace ivoa::logio {

std::string session_name_of(const std::string& log_path);

// Whether the file is a split part (its name ends in .NN, as lcm-logger's
// and ivoa-logger's --split parts do).
bool is_split_part(const std::string& log_path);

// "NAME.02 before NAME.01" for the first split part in `logs` that comes
// after a later part of the same recording (same folder and name), or "":
// a list written by hand, where a shell's glob would have sorted them.
std::string split_parts_out_of_order(const std::vector<std::string>& logs);

}  // namespace ivoa::logio
