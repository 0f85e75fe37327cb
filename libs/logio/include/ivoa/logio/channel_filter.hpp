#pragma once
// Which channels a log tool takes (the logger records, the player plays): those matching an include regex and
// not an exclude regex (ECMAScript syntax, matched against the whole name,
// as LCM anchors its own channel regexes), plus channels that are always
// recorded whatever the regexes say (the rig calibration, so that every
// log is self-contained). Decisions are cached per channel name, so the
// regexes run once per channel, not once per message.
#include <regex>
#include <string>
#include <unordered_map>
#include <vector>

namespace ivoa::logio {

class ChannelFilter {
 public:
  // Throws std::invalid_argument naming the bad regex. Empty exclude: none.
  ChannelFilter(const std::string& include, const std::string& exclude, std::vector<std::string> always = {});

  // Not thread-safe: call from the receive thread only.
  bool accepts(const std::string& channel);

 private:
  bool decide(const std::string& channel) const;

  std::regex include_;
  std::regex exclude_;
  bool has_exclude_;
  std::vector<std::string> always_;
  std::unordered_map<std::string, bool> decisions_;
};

}  // namespace ivoa::logio
