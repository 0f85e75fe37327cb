#pragma once
// Checks a received introspection_t before anything draws or scores it.
#include <string>

#include "ivoa/introspection_t.hpp"

namespace ivoa {

// Empty if the message's content can be used, otherwise the first thing
// wrong: a heatmap whose rows x cols is not its cells, a class probability
// that is not a number in [0, 1], a variance that is not finite and >= 0, a
// query whose position is not finite, whose pixel lies outside any image,
// whose probability, uncertainty or (given a verdict) P(wrong) and its
// variance are not those, whose announced flags are not 0 or 1, or whose
// class, verdict or class given the verdict is none of the labels or states.
std::string introspection_content_error(const introspection_t& msg);

}  // namespace ivoa
