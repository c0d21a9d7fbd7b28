// A small JSON reader for the policy metadata (`ernest_metadata.json` in the TorchScript archive,
// written by python/ernest_cpp/rl/export.py). Reads any RFC 8259 document; kept in the runtime so
// that onboard builds need no extra dependency.
#pragma once

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace ernest::runtime::json {

class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Value {
  enum class Type { Null, Bool, Number, String, Array, Object };
  Type type = Type::Null;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<Value> array;
  std::map<std::string, Value> object;

  bool is_number() const { return type == Type::Number; }
  bool is_string() const { return type == Type::String; }
  bool is_array() const { return type == Type::Array; }
  bool is_object() const { return type == Type::Object; }
  /// Member `key` of an object, or nullptr if absent (or not an object).
  const Value* find(const std::string& key) const;
};

/// Parse a whole document; throws ParseError naming the offset of the first problem.
Value parse(const std::string& text);

}  // namespace ernest::runtime::json
