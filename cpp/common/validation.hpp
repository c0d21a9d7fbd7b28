// Parameter checks shared by every options/parameters struct: each failure names the field, its
// value and the allowed range, so a Python user sees e.g.
//   ValueError: SoilParameters.cohesion = -5 is outside the allowed range [0, inf)
#pragma once

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace ernest {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Throws std::invalid_argument unless `value` is finite and lo <= value <= hi.
inline void require_in_range(const char* owner, const char* field, double value, double lo,
                             double hi) {
  if (std::isfinite(value) && value >= lo && value <= hi) return;
  std::ostringstream os;
  os << owner << "." << field << " = " << value << " is outside the allowed range [" << lo << ", ";
  if (hi == kInf) os << "inf";
  else os << hi;
  os << "]";
  if (!std::isfinite(value)) os << " (must be finite)";
  throw std::invalid_argument(os.str());
}

/// Throws std::invalid_argument unless `value` is finite and strictly positive.
inline void require_positive(const char* owner, const char* field, double value) {
  if (std::isfinite(value) && value > 0.0) return;
  std::ostringstream os;
  os << owner << "." << field << " = " << value << " must be finite and > 0";
  throw std::invalid_argument(os.str());
}

/// Throws std::invalid_argument if `value` is NaN or infinite (for run-time inputs).
inline void require_finite(const char* owner, const char* field, double value) {
  if (std::isfinite(value)) return;
  std::ostringstream os;
  os << owner << "." << field << " = " << value << " is not finite";
  throw std::invalid_argument(os.str());
}

/// Throws std::invalid_argument with a free-form message when `ok` is false. A literal message
/// picks this overload: nothing is built unless the check fails, so it is free in hot loops (the
/// 400 Hz runtime loop calls FtsProcessor::update every tick and must not allocate).
inline void require(bool ok, const char* message) {
  if (!ok) throw std::invalid_argument(message);
}

/// As above for a message built by the caller. The argument is built before the call even when
/// the check passes: keep it out of per-step code (use the const char* overload or test first).
inline void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

}  // namespace ernest
