// Bad input: a scene file, key or value outside what is allowed. Commands exit with code 2.
#pragma once

#include <stdexcept>
#include <string>

namespace dicesim {

class SceneError : public std::runtime_error {
 public:
  // file: the scene file (or "--set"); key: dotted key path; value: what was given;
  // allowed: the allowed range or form, in words.
  SceneError(std::string file, std::string key, std::string value, std::string allowed)
      : std::runtime_error(file + ": " + (key.empty() ? "" : key + (value.empty() ? "" : " = " + value) + ": ") + allowed),
        file_(std::move(file)), key_(std::move(key)), value_(std::move(value)), allowed_(std::move(allowed)) {}

  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& allowed() const { return allowed_; }

 private:
  std::string file_, key_, value_, allowed_;
};

}  // namespace dicesim
