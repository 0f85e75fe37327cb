#include "ivoa/logger/split_log.hpp"

#include <cstdio>

#include <spdlog/spdlog.h>

#include "ivoa/core/time.hpp"
#include "ivoa/logio/log_format.hpp"

namespace ivoa::logger {

SplitLog::SplitLog(SplitLogOptions options, SessionCounters& counters)
    : options_(std::move(options)), counters_(counters) {
  open_part(0, 0);
}

SplitLog::~SplitLog() = default;

std::string SplitLog::part_path(const SplitLogOptions& options, int part) {
  if (options.split_bytes == 0) return options.path;
  char suffix[16];
  std::snprintf(suffix, sizeof(suffix), ".%02d", part);
  return options.path + suffix;
}

void SplitLog::open_part(int part, int64_t timestamp) {
  logio::LogWriterOptions writer_options;
  writer_options.overwrite = options_.overwrite;
  writer_ = std::make_unique<logio::LogWriter>(part_path(options_, part), writer_options);
  files_.push_back(writer_->path());
  counters_.files.fetch_add(1);
  summary_ = logio::LogSummary();
  starts_with_calibration_ = false;
  if (calibration_) {
    // The copy carries the new file's first timestamp, so a replay of this
    // file alone does not pause before its first real event.
    write_to_current(calibration_->channel, timestamp, calibration_->data);
  }
  opening_bytes_ = writer_->bytes();
  opening_events_ = summary_.events();
  update_sidecar(false, "");
  spdlog::info("logging to {}", writer_->path());
}

void SplitLog::write(const RecordedEvent& event) {
  replace_if_deleted(event.timestamp);
  const uint64_t event_bytes = logio::kEventHeaderBytes + event.bytes();
  const bool full = options_.split_bytes > 0 && writer_->bytes() > opening_bytes_ &&
                    writer_->bytes() + event_bytes > options_.split_bytes;
  if (full) {
    close();
    open_part(static_cast<int>(files_.size()), event.timestamp);
  }
  write_to_current(event.channel, event.timestamp, event.data);
  if (!options_.calibration_channel.empty() && event.channel == options_.calibration_channel) calibration_ = event;
  if (monotonic_ms() - sidecar_written_ms_ >= options_.sidecar_refresh_s * 1000.0) update_sidecar(false, "");
}

// A file deleted while written (by hand, a clean-up script) keeps taking
// events that vanish with it at close; before each event (an fstat, about
// a microsecond) the logger looks, and starts a file of that name again: the
// loss is said and counted, and what comes after is kept. Where the folder
// is gone too, that is a write error.
void SplitLog::replace_if_deleted(int64_t timestamp) {
  if (!writer_->deleted()) return;
  const int64_t lost = summary_.events() - opening_events_;
  counters_.deleted.fetch_add(lost);
  spdlog::error(
      "{} was deleted while recording: its {} messages are lost; recording goes on in a new file of that name",
      writer_->path(), lost);
  writer_.reset();
  files_.pop_back();
  counters_.files.fetch_sub(1);
  open_part(static_cast<int>(files_.size()), timestamp);
}

void SplitLog::write_to_current(const std::string& channel, int64_t timestamp, const std::vector<uint8_t>& data) {
  try {
    writer_->write(channel, timestamp, data.data(), data.size());
  } catch (const logio::LogWriteError& e) {
    update_sidecar(false, e.what());
    throw;
  }
  if (summary_.events() == 0) starts_with_calibration_ = channel == options_.calibration_channel;
  summary_.add(channel, timestamp, data.data(), data.size());
  counters_.bytes_written.fetch_add(static_cast<int64_t>(channel.size() + data.size()));
}

void SplitLog::close(const std::string& error) {
  if (!writer_ || !writer_->is_open()) return;
  try {
    writer_->close();
  } catch (const logio::LogWriteError& e) {
    update_sidecar(false, error.empty() ? e.what() : error);
    throw;
  }
  update_sidecar(error.empty(), error);
}

void SplitLog::update_sidecar(bool complete, const std::string& error) {
  if (!options_.sidecars) return;
  SidecarContent content;
  content.identity = &options_.identity;
  content.log_path = writer_->path();
  content.part = static_cast<int>(files_.size()) - 1;
  content.complete = complete;
  content.error = error;
  content.starts_with_calibration = starts_with_calibration_;
  content.file_bytes = writer_->bytes();
  content.summary = &summary_;
  content.counters = &counters_;
  sidecar_written_ms_ = monotonic_ms();
  std::string problem;
  if (!write_sidecar(content, problem)) spdlog::warn("{} (the log itself is not affected)", problem);
}

}  // namespace ivoa::logger
