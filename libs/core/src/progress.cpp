#include "ivoa/core/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "ivoa/core/time.hpp"

namespace ivoa {
namespace {

constexpr double kEtaAfterS = 1.0;

std::string duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof(buf), "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof(buf), "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else if (s < 1e6 * 3600)  // an int of seconds overflowed past 68 years: "ETA -596523h-14m"
    std::snprintf(buf, sizeof(buf), "%lldh%02lldm", static_cast<long long>(s) / 3600,
                  static_cast<long long>(s) % 3600 / 60);
  else std::snprintf(buf, sizeof(buf), "over 10^6 h");
  return buf;
}

}  // namespace

Progress::Progress(std::string label, double total, std::string unit, double print_every_s)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      start_ms_(monotonic_ms()),
      print_every_ms_(print_every_s * 1000.0),
      tty_(isatty(STDERR_FILENO) == 1) {}

Progress::~Progress() {
  if (!finished_ && tty_) std::fprintf(stderr, "\n");
}

std::string Progress::line(double done, const std::string& detail) const {
  const double elapsed_s = (monotonic_ms() - start_ms_) / 1000.0;
  const double rate = elapsed_s > 0 ? done / elapsed_s : 0;
  char buf[256];
  if (total_ > 0) {
    // A rate from the first moments (opening files, a first tiny read) once
    // promised 21 minutes for a 1 s job: no ETA before kEtaAfterS.
    const double eta = rate > 0 && elapsed_s >= kEtaAfterS ? (total_ - done) / rate : NAN;
    std::snprintf(buf, sizeof(buf), "%s: %.0f/%.0f %s (%.0f%%), %.1f %s/s, elapsed %s, ETA %s", label_.c_str(), done,
                  total_, unit_.c_str(), 100.0 * done / total_, rate, unit_.c_str(), duration(elapsed_s).c_str(),
                  duration(eta).c_str());
  } else {
    std::snprintf(buf, sizeof(buf), "%s: %.0f %s, %.1f %s/s, elapsed %s", label_.c_str(), done, unit_.c_str(), rate,
                  unit_.c_str(), duration(elapsed_s).c_str());
  }
  return detail.empty() ? std::string(buf) : std::string(buf) + ", " + detail;
}

void Progress::update(double done, const std::string& detail) {
  done_ = done;
  const double now = monotonic_ms();
  const double every = tty_ ? 200.0 : print_every_ms_;
  if (now - last_print_ms_ < every) return;
  last_print_ms_ = now;
  if (tty_) std::fprintf(stderr, "\r\033[K%s", line(done, detail).c_str());
  else std::fprintf(stderr, "%s\n", line(done, detail).c_str());
  std::fflush(stderr);
}

void Progress::finish(const std::string& detail) {
  if (finished_) return;
  finished_ = true;
  if (tty_) std::fprintf(stderr, "\r\033[K");
  std::fprintf(stderr, "%s\n", line(done_, detail).c_str());
}

}  // namespace ivoa
