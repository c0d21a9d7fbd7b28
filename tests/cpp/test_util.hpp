// Helpers shared by the C++ tests.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace ernest::testing {

/// The message of the std::invalid_argument that fn throws, or "" if it throws none.
inline std::string invalid_argument_message(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace ernest::testing
