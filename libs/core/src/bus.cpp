#include "ivoa/core/bus.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "ivoa/core/message_registry.hpp"

namespace ivoa {

std::string with_receive_buffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  const char sep = url.find('?') == std::string::npos ? '?' : '&';
  return url + sep + "recv_buf_size=" + std::to_string(kReceiveBufferBytes);
}

std::string default_lcm_url() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return with_receive_buffer(env && *env ? env : kProjectDefaultUrl);
}

namespace {

// Why LCM would not start on `url`, as far as can be told from outside it.
std::string why_not_writable(const std::string& path) {
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (std::filesystem::is_directory(path)) return "'" + path + "' is a folder, not a log file";
  if (!folder.empty() && !std::filesystem::is_directory(folder))
    return "cannot write the log '" + path + "': its folder " + folder.string() + " does not exist";
  return "cannot write the log '" + path + "' (may this user write in its folder?)";
}

BusError cannot_start(const std::string& url) {
  const std::string what = "cannot start LCM on '" + url + "'";
  if (url.rfind("file://", 0) == 0) {
    const std::string rest = url.substr(7);
    const std::string path = rest.substr(0, rest.find('?'));
    const bool reading = rest.find("mode=w") == std::string::npos && rest.find("mode=a") == std::string::npos;
    if (reading && !std::filesystem::exists(path))
      return BusError(what + ": the log '" + path + "' does not exist", kExitBadInput);
    if (reading) return BusError(what + ": cannot read the log '" + path + "'", kExitBadInput);
    return BusError(what + ": " + why_not_writable(path), kExitIoError);
  }
  if (url.rfind("udpm://", 0) == 0) {
    const std::string rest = url.substr(7);
    const std::string group = rest.substr(0, rest.find_first_of(":?"));
    in_addr address{};
    if (!group.empty() && (::inet_aton(group.c_str(), &address) == 0 || !IN_MULTICAST(ntohl(address.s_addr))))
      return BusError(what + ": '" + group + "' is not a multicast group (224.0.0.0 to 239.255.255.255)", kExitUsage);
    return BusError(what + ": is there a multicast route? e.g. ip route add 224.0.0.0/4 dev lo");
  }
  return BusError(
      what + " (LCM URLs: udpm://GROUP:PORT?ttl=0, file://LOG?speed=1 to replay, file://LOG?mode=w, memq://)",
      kExitUsage);
}

// A udpm port LCM cannot use ("" if the URL gives a usable one or none):
// 99999 was taken for a missing multicast route, and 0 passed LCM's start
// and failed at the first subscription, 10 s later.
std::string bad_udpm_port(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0) return "";
  const std::string address = url.substr(7, url.find('?') - 7);
  const size_t colon = address.find(':');
  if (colon == std::string::npos) return "";
  const std::string port = address.substr(colon + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (digits && std::stoi(port) >= 1 && std::stoi(port) <= 65535) return "";
  return "cannot start LCM on '" + url + "': port '" + port + "' is not 1 to 65535";
}

}  // namespace

// Owns the std::function; LCM's C API calls it through `user`.
struct Bus::Subscription {
  RawHandler handler;
  static void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
    static_cast<Subscription*>(user)->handler(rbuf->data, rbuf->data_size,
                                              ReceiveInfo{channel, rbuf->recv_utime, rbuf->data_size});
  }
};

std::string effective_lcm_url(const std::string& given) {
  return given.empty() ? default_lcm_url() : with_receive_buffer(given);
}

Bus::Bus(const std::string& url) : url_(effective_lcm_url(url)) {
  if (const std::string why = bad_udpm_port(url_); !why.empty()) throw BusError(why, kExitUsage);
  lcm_ = std::make_unique<lcm::LCM>(url_);
  if (!lcm_->good()) throw cannot_start(url_);
}

Bus::~Bus() = default;

bool Bus::publish_raw(std::string_view channel, const void* data, size_t size) {
  std::lock_guard<std::mutex> lock(publish_mutex_);
  return lcm_->publish(std::string(channel), data, static_cast<unsigned int>(size)) == 0;
}

// Through the C API: lcm::LCM::subscribe returns a subscription even when
// the regex does not compile, and using it then crashes.
void Bus::subscribe_raw(std::string_view channel_regex, RawHandler handler) {
  auto sub = std::make_unique<Subscription>();
  sub->handler = std::move(handler);
  const std::string regex(channel_regex);
  lcm_subscription_t* s = lcm_subscribe(lcm_->getUnderlyingLCM(), regex.c_str(), &Subscription::on_message, sub.get());
  if (s == nullptr) {
    const char* why = "not a valid channel regex (GLib syntax, matched against the whole channel name)";
    throw BusError("cannot subscribe to '" + regex + "': " + why);
  }
  // Images arrive in bursts; keep more than LCM's default 30 queued per
  // subscription so short stalls do not drop messages.
  lcm_subscription_set_queue_capacity(s, 120);
  subscriptions_.push_back(std::move(sub));
}

std::string replayed_log(const std::string& url) {
  if (url.rfind("file://", 0) != 0 || url.find("mode=w") != std::string::npos ||
      url.find("mode=a") != std::string::npos)
    return "";
  return url.substr(7, url.find('?') - 7);
}

bool Bus::reads_a_log() const { return !replayed_log(url_).empty(); }

int Bus::handle(int timeout_ms) { return lcm_->handleTimeout(timeout_ms); }

std::string Bus::decode_error_text(const std::string& channel, const std::string& type, const void* data, size_t size) {
  std::string why;
  if (const auto other = payload_type_name(data, size); other && *other != type)
    why = "it is an " + std::string(*other) + " (another type on this channel)";
  else if (other) why = "truncated or damaged inside";
  else why = "an unknown type's fingerprint (another program's type, or damaged at its start)";
  return "channel " + channel + ": " + std::to_string(size) + "-byte message does not decode as " + type + ": " + why;
}

void Bus::report_decode_error(const std::string& what) {
  if (decode_error_handler_) decode_error_handler_(what);
  else spdlog::warn("{}", what);
}

}  // namespace ivoa
