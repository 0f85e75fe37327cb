#pragma once
// Checks for flags whose errors a user can read. CLI11 2.1's
// PositiveNumber and NonNegativeNumber name the double range they test
// against, 300 digits long; these say "--steps: must be > 0, not 0".
#include <CLI/CLI.hpp>
#include <string>

namespace ivoa {

// A finite number (help: NUMBER): not nan or inf.
const CLI::Validator& finite_number();
// A finite number > 0 (help: POSITIVE). Infinities are refused: no flag
// means "no limit" by inf, and some hang a library (cv::VideoWriter's fps).
const CLI::Validator& positive_number();
// A finite number >= 0 (help: NONNEGATIVE).
const CLI::Validator& non_negative_number();
// A number in [lo, hi] (help: "NUMBER in [lo, hi]"). CLI::Range lets NaN
// through, and names its bounds with six decimals.
CLI::Validator number_in(double lo, double hi);
// A seed: decimal digits, 0 to 999999999999999999 (help: SEED). CLI11
// wraps "-1" and saturates a 20-digit number into an unsigned flag, so
// different seeds ran as the same session.
const CLI::Validator& seed_number();
// A channel to publish on: 1 to 63 characters, LCM's limit (help: CHANNEL).
// LCM refused a longer one with a line on stderr, and the process counted
// every message as published.
const CLI::Validator& channel_name();
// Channels to subscribe to: a regex in LCM's syntax (GLib's), matched
// against whole names (help: REGEX). LCM refused a bad one only once the
// process had started, in a message that did not name the flag.
const CLI::Validator& channel_regex();
// A log's channel that an offline tool reads, by its exact name, in the
// "Channels" group with its default shown: logs of a robot whose processes
// were started with renamed channels stay readable.
CLI::Option* add_log_channel_option(CLI::App& app, const std::string& flag, std::string& channel,
                                    const std::string& what);
// A whole number >= 1 that is odd, e.g. a filter window (help: ODD).
const CLI::Validator& odd_positive_integer();
// A file (help: FILE) or folder (DIR) to read, which must exist. Unlike
// CLI11's ExistingFile, a missing one is an unusable input, exit 3 as for
// one that cannot be read (parse_command_line asks is_missing_input), not a
// flag error (exit 2).
const CLI::Validator& input_file();
const CLI::Validator& input_folder();
bool is_missing_input(const CLI::ParseError& e);

}  // namespace ivoa
