#pragma once
// The LCM layer every process uses (after Drake's DrakeLcm): one small
// interface to publish, subscribe and handle with a timeout. The transport
// is picked by URL, so the same code runs on UDP multicast (udpm://, live),
// in memory (memq://, unit tests) and on a log (file://...?mode=r|w).
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "ivoa/core/message_counts.hpp"
#include "ivoa/core/message_decode.hpp"
#include "ivoa/core/process.hpp"

namespace ivoa {

// Receive buffer for udpm subscribers: a 960x600 RGB pair is ~3.5 MB and is
// lost whole with the kernel's default 208 KB buffer (lcm_notes.md §2.3).
inline constexpr int kReceiveBufferBytes = 16 * 1024 * 1024;
inline constexpr const char* kProjectDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";

// The URL to use when none is given: $LCM_DEFAULT_URL or the project
// default, with a large receive buffer added to any udpm URL lacking one.
std::string default_lcm_url();
std::string with_receive_buffer(const std::string& url);
// The URL a Bus opens for a --lcm-url: default_lcm_url() for "", else the
// URL given with the same receive buffer (a viewer on a robot's own port
// lost most stereo pairs in the kernel without it, uncounted).
std::string effective_lcm_url(const std::string& given);

// The log a file:// URL replays (not mode=w or mode=a), or "" for a URL that
// replays none.
std::string replayed_log(const std::string& url);

class BusError : public std::runtime_error {
 public:
  explicit BusError(const std::string& what, int exit_code = kExitFailure)
      : std::runtime_error(what), exit_code_(exit_code) {}
  // What a process exits with: kExitBadInput for a log that cannot be read
  // (file://), kExitIoError for one that cannot be written, else kExitFailure.
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

struct ReceiveInfo {
  std::string channel;
  int64_t recv_utime = 0;  // local receive time (replay time on a log)
  size_t bytes = 0;
};

class Bus {
 public:
  using RawHandler = std::function<void(const void* data, size_t size, const ReceiveInfo&)>;
  using ErrorHandler = std::function<void(const std::string& what)>;

  // Empty url = default_lcm_url(). Throws BusError if LCM cannot start, with
  // the likely reason: for udpm no multicast route, for file:// no such log.
  explicit Bus(const std::string& url = "");
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  // Sets the message's length fields from its vectors, encodes, publishes.
  // Safe to call from any thread. Returns false if LCM refused it.
  template <class Msg>
  bool publish(std::string_view channel, Msg& msg) {
    set_counts(msg);
    std::vector<uint8_t> buffer(static_cast<size_t>(msg.getEncodedSize()));
    if (msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())) < 0) return false;
    return publish_raw(channel, buffer.data(), buffer.size());
  }
  bool publish_raw(std::string_view channel, const void* data, size_t size);

  // Typed subscription. A payload that does not decode as Msg (wrong type,
  // truncated) is reported to the decode-error handler, never to the handler.
  template <class Msg>
  void subscribe(std::string_view channel, std::function<void(const Msg&, const ReceiveInfo&)> handler) {
    const std::string type = std::string("ivoa.") + Msg::getTypeName();
    subscribe_raw(channel, [this, type, handler](const void* data, size_t size, const ReceiveInfo& info) {
      Msg msg;
      if (!decode_message(msg, data, size)) {
        report_decode_error(decode_error_text(info.channel, type, data, size));
        return;
      }
      handler(msg, info);
    });
  }
  // channel_regex is an LCM (GLib) regex, implicitly anchored.
  void subscribe_raw(std::string_view channel_regex, RawHandler handler);
  // Where undecodable messages are reported; default: a warning in the log.
  void on_decode_error(ErrorHandler handler) { decode_error_handler_ = std::move(handler); }

  // Dispatches at most one message: >0 handled, 0 timeout, <0 error or end of log.
  // Call from one thread only.
  int handle(int timeout_ms);

  const std::string& url() const { return url_; }
  // True on a file:// URL opened for reading: handle() < 0 then means the
  // log has ended, and a process should finish as it would at a stop.
  bool reads_a_log() const;
  lcm::LCM& lcm() { return *lcm_; }
  // What a payload that did not decode as `type` is, by its fingerprint.
  static std::string decode_error_text(const std::string& channel, const std::string& type, const void* data,
                                       size_t size);

 private:
  struct Subscription;
  void report_decode_error(const std::string& what);

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::mutex publish_mutex_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  ErrorHandler decode_error_handler_;
};

}  // namespace ivoa
