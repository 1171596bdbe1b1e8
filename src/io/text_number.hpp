// Internal: strict text number parsing and shortest round-trip formatting shared by the OBJ, PLY
// and OFF readers and writers. std::from_chars/to_chars: locale-free, exact and fast.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

namespace limn::text {

// Bytes from a file can be anything; messages stay one printable ASCII line.
inline std::string printable(std::string_view s) {
  std::string out;
  for (const char c : s.substr(0, 32)) {
    const auto u = static_cast<unsigned char>(c);
    out += (u < 32 || u >= 127) ? '?' : c;
  }
  if (s.size() > 32) out += "...";
  return out;
}

inline std::string_view strip_plus(std::string_view t) {
  // from_chars rejects a leading '+', which printf-style writers may emit; "+-1" stays invalid.
  if (t.size() > 1 && t[0] == '+' && t[1] != '-' && t[1] != '+') t.remove_prefix(1);
  return t;
}

inline bool parse_int(std::string_view t, int64_t& out) {
  t = strip_plus(t);
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  return ec == std::errc() && ptr == t.data() + t.size();
}

// from_chars reports overflow and underflow alike as out of range; the decimal exponent of the
// leading significant digit tells them apart (negative: a legitimate zero, not an error).
inline bool underflows(std::string_view t) {
  size_t i = (!t.empty() && (t[0] == '-' || t[0] == '+')) ? 1 : 0;
  int64_t mag = 0, zeros = 0;
  bool point = false, lead = false;
  for (; i < t.size() && (t[i] == '.' || (t[i] >= '0' && t[i] <= '9')); ++i) {
    if (t[i] == '.')
      point = true;
    else if (lead)
      mag += point ? 0 : 1;
    else if (t[i] != '0')
      lead = true, mag = point ? -(zeros + 1) : 0;
    else if (point)
      ++zeros;
  }
  int64_t exp = 0;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    const std::string_view e = t.substr(i + 1);
    const auto r =
        std::from_chars(e.data() + (e.starts_with('+') ? 1 : 0), e.data() + e.size(), exp);
    if (r.ec == std::errc::result_out_of_range) exp = e.starts_with('-') ? INT32_MIN : INT32_MAX;
  }
  return mag + exp < 0;
}

inline bool parse_double(std::string_view t, double& out) {
  t = strip_plus(t);
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  if (ptr != t.data() + t.size() || t.empty()) return false;
  if (ec == std::errc::result_out_of_range) {
    const bool tiny = underflows(t);
    out = t[0] == '-' ? (tiny ? -0.0 : -INFINITY) : (tiny ? 0.0 : INFINITY);
    return true;  // an overflow is reported by the caller as a non-finite value
  }
  return ec == std::errc();
}

// Parses a float token the way a float32 writer meant it: directly, not through double, so
// shortest-representation output reads back bit-exact.
inline bool parse_float(std::string_view t, float& out) {
  t = strip_plus(t);
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  if (ptr != t.data() + t.size() || t.empty()) return false;
  if (ec == std::errc::result_out_of_range) {
    const bool tiny = underflows(t);
    out = t[0] == '-' ? (tiny ? -0.0f : -INFINITY) : (tiny ? 0.0f : INFINITY);
    return true;
  }
  return ec == std::errc();
}

// Parsed as float directly (not via double) so shortest-representation output reads back exactly.
// Underflow is a legitimate zero; overflow, NaN and infinities are rejected.
inline bool parse_finite(std::string_view t, float& out) {
  return parse_float(t, out) && std::isfinite(out);
}

inline void put_float(std::string& out, float x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

inline void put_uint(std::string& out, uint64_t x) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

}  // namespace limn::text
