#include "ivoa/core/flag_checks.hpp"

#include <cmath>
#include <string>

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

const CLI::Validator& odd_positive_integer() {
  static const CLI::Validator check(
      [](std::string& text) {
        return check_number(
            text, [](double v) { return v >= 1 && std::fmod(v, 2.0) == 1.0; }, "must be an odd whole number >= 1");
      },
      "ODD");
  return check;
}

}  // namespace ivoa
