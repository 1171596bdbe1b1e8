// Image sizes on the command line ("WxH"), shared by limn and limn-view.
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "limn/mesh/mesh.hpp"

namespace limn::app {

/// "WxH" -> w, h, each in [lo, hi]; InputError naming `option` and an `example` otherwise.
inline void parse_image_size(const std::string& s, const char* option, const char* example, int lo,
                             int hi, int& w, int& h) {
  const size_t x = s.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument(s);
    size_t a = 0, b = 0;
    w = std::stoi(s.substr(0, x), &a);
    h = std::stoi(s.substr(x + 1), &b);
    if (a != x || b != s.size() - x - 1) throw std::invalid_argument(s);
  } catch (const std::exception&) {
    throw InputError(fmt::format("{} {}: expected WxH, such as {}", option, s, example));
  }
  if (w < lo || h < lo || w > hi || h > hi)
    throw InputError(fmt::format("{} {}: {}-{} pixels each way", option, s, lo, hi));
}

}  // namespace limn::app
