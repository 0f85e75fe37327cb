#pragma once
// Shared by the integration-test checkers: a flat JSON writer and the
// latest heartbeat of the driver under test.
#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "ivoa/core/bus.hpp"
#include "ivoa/core/channels.hpp"
#include "ivoa/core/json_text.hpp"
#include "ivoa/process_status_t.hpp"

namespace ivoa::test {

// {"key": value, ...} with numbers, strings and one level of nested objects.
class JsonObject {
 public:
  void set(const std::string& key, double value) { fields_[key] = format_number(value); }
  void set(const std::string& key, int64_t value) { fields_[key] = std::to_string(value); }
  void set(const std::string& key, int value) { fields_[key] = std::to_string(value); }
  void set(const std::string& key, bool value) { fields_[key] = value ? "true" : "false"; }
  void set(const std::string& key, const std::string& value) { fields_[key] = json_quote(value); }
  void set(const std::string& key, const char* value) { fields_[key] = json_quote(value); }
  void set(const std::string& key, const JsonObject& value) { fields_[key] = value.str(); }

  std::string str() const {
    std::ostringstream out;
    out << "{";
    bool first = true;
    for (const auto& [k, v] : fields_) {
      out << (first ? "" : ", ") << json_quote(k) << ": " << v;
      first = false;
    }
    out << "}";
    return out.str();
  }
  void write(const std::string& path) const { std::ofstream(path) << str() << "\n"; }

 private:
  static std::string format_number(double v) {
    std::ostringstream out;
    out.precision(10);
    out << v;
    return out.str();
  }
  std::map<std::string, std::string> fields_;
};

// Keeps the most recent PROCESS_STATUS of one process.
class StatusWatcher {
 public:
  StatusWatcher(Bus& bus, std::string process_name) : name_(std::move(process_name)) {
    bus.subscribe<process_status_t>(channels::kProcessStatus, [this](const process_status_t& s, const ReceiveInfo&) {
      if (s.name != name_) return;
      latest_ = s;
      ++count_;
    });
  }
  // The process published its last heartbeat (it exits after it).
  bool finished() const { return count_ > 0 && (latest_.state == "stopped" || latest_.state == "failed"); }

  JsonObject json() const {
    JsonObject o;
    o.set("heartbeats", count_);
    if (count_ == 0) return o;
    o.set("state", latest_.state);
    o.set("messages_in", latest_.messages_in);
    o.set("messages_out", latest_.messages_out);
    o.set("dropped", latest_.dropped);
    o.set("bad_input", latest_.bad_input);
    o.set("last_error", latest_.last_error);
    JsonObject counters;
    for (int i = 0; i < latest_.num_counters; ++i) counters.set(latest_.counter_names[i], latest_.counter_values[i]);
    o.set("counters", counters);
    return o;
  }

 private:
  std::string name_;
  process_status_t latest_;
  int64_t count_ = 0;
};

}  // namespace ivoa::test
