#pragma once
// Progress for long offline work: done/total, rate, ETA. On a terminal it
// redraws one line; otherwise (logs, CI) it prints a line every few seconds.
#include <cstdint>
#include <string>

namespace ivoa {

class Progress {
 public:
  // `unit` names what `done` counts ("frames", "MB", "steps").
  Progress(std::string label, double total, std::string unit, double print_every_s = 5.0);
  ~Progress();

  // Sets the amount done; `detail` is appended (e.g. "loss 0.41").
  void update(double done, const std::string& detail = "");
  void finish(const std::string& detail = "");
  std::string line(double done, const std::string& detail) const;

 private:
  std::string label_, unit_;
  double total_;
  double start_ms_, last_print_ms_ = -1e18, print_every_ms_;
  double done_ = 0;
  bool tty_;
  bool finished_ = false;
};

}  // namespace ivoa
