#include "ivoa/core/flag_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <glib.h>

#include "ivoa/core/channels.hpp"

namespace ivoa {
namespace {

// "" if `text` is a number that `ok` accepts, else what is wrong.
template <class Ok>
std::string check_number(const std::string& text, Ok ok, const char* must) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || std::isnan(value)) return "must be a number, not '" + text + "'";
  return ok(value) ? std::string() : std::string(must) + ", not " + text;
}

// 0.05, 1e+09: bounds as a user would type them.
std::string short_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

}  // namespace

const CLI::Validator& finite_number() {
  static const CLI::Validator check(
      [](std::string& text) {
        return check_number(
            text, [](double v) { return std::isfinite(v); }, "must be finite");
      },
      "NUMBER");
  return check;
}

const CLI::Validator& positive_number() {
  static const CLI::Validator check(
      [](std::string& text) {
        return check_number(
            text, [](double v) { return v > 0 && std::isfinite(v); }, "must be > 0 and finite");
      },
      "POSITIVE");
  return check;
}

const CLI::Validator& non_negative_number() {
  static const CLI::Validator check(
      [](std::string& text) {
        return check_number(
            text, [](double v) { return v >= 0 && std::isfinite(v); }, "must be >= 0 and finite");
      },
      "NONNEGATIVE");
  return check;
}

CLI::Validator number_in(double lo, double hi) {
  const std::string range = "[" + short_text(lo) + ", " + short_text(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) {
        return check_number(
            text, [lo, hi](double v) { return v >= lo && v <= hi; }, ("must be in " + range).c_str());
      },
      "NUMBER in " + range);
}

const CLI::Validator& seed_number() {
  static const CLI::Validator check(
      [](std::string& text) {
        const bool digits = !text.empty() && text.size() <= 18 &&
                            std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
        return digits ? std::string() : "must be a whole number 0 to 999999999999999999, not " + text;
      },
      "SEED");
  return check;
}

const CLI::Validator& channel_name() {
  static const CLI::Validator check(
      [](std::string& text) {
        if (!text.empty() && text.size() <= channels::kMaxChannelLength) return std::string();
        return "must be a channel name of 1 to " + std::to_string(channels::kMaxChannelLength) +
               " characters (LCM's limit), not " + std::to_string(text.size()) + " characters";
      },
      "CHANNEL");
  return check;
}

CLI::Option* add_log_channel_option(CLI::App& app, const std::string& flag, std::string& channel,
                                    const std::string& what) {
  return app.add_option(flag, channel, "the log's channel of " + what)
      ->capture_default_str()
      ->group("Channels")
      ->check(channel_name());
}

const CLI::Validator& channel_regex() {
  static const CLI::Validator check(
      [](std::string& text) {
        GError* error = nullptr;
        GRegex* regex = g_regex_new(("^(" + text + ")$").c_str(), static_cast<GRegexCompileFlags>(0),
                                    static_cast<GRegexMatchFlags>(0), &error);
        std::string why;
        if (regex == nullptr)
          why = std::string("is not a channel regex (GLib's syntax): ") + (error ? error->message : "?");
        if (regex) g_regex_unref(regex);
        if (error) g_error_free(error);
        return why;
      },
      "REGEX");
  return check;
}

const CLI::Validator& odd_positive_integer() {
  static const CLI::Validator check(
      [](std::string& text) {
        return check_number(
            text, [](double v) { return v >= 1 && std::fmod(v, 2.0) == 1.0; }, "must be an odd whole number >= 1");
      },
      "ODD");
  return check;
}

namespace {

// Begins every message of input_file() and input_folder(), so that
// is_missing_input can tell their errors from other flags'.
constexpr const char* kMissingInput = "cannot be read: ";

CLI::Validator input_path(bool folder) {
  return CLI::Validator(
      [folder](std::string& text) {
        std::error_code error;
        const auto status = std::filesystem::status(text, error);
        if (error && error != std::errc::no_such_file_or_directory)  // a folder on the way that cannot be read
          return std::string(kMissingInput) + text + ": " + error.message();
        if (!std::filesystem::exists(status)) return std::string(kMissingInput) + "no such file or folder: " + text;
        if (folder && !std::filesystem::is_directory(status))
          return std::string(kMissingInput) + text + " is a file, not a folder";
        if (!folder && std::filesystem::is_directory(status))
          return std::string(kMissingInput) + text + " is a folder, not a file";
        return std::string();
      },
      folder ? "DIR" : "FILE");
}

}  // namespace

const CLI::Validator& input_file() {
  static const CLI::Validator check = input_path(false);
  return check;
}

const CLI::Validator& input_folder() {
  static const CLI::Validator check = input_path(true);
  return check;
}

bool is_missing_input(const CLI::ParseError& e) {
  return dynamic_cast<const CLI::ValidationError*>(&e) != nullptr &&
         std::string(e.what()).find(kMissingInput) != std::string::npos;
}

}  // namespace ivoa
