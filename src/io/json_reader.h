#pragma once
// Strict reading of JSON objects into parameter structs: every key read is marked, and `finish()`
// rejects any key left over, naming its JSON path and the closest valid key ("did you mean").
#include "core/error.h"
#include "core/types.h"

#include <nlohmann/json.hpp>

#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace ff::io {

/// Levenshtein edit distance (for "did you mean").
std::size_t edit_distance(std::string_view a, std::string_view b);
/// The candidate closest to `key`, or "" when none is close enough to be a likely typo.
std::string closest_key(std::string_view key, const std::vector<std::string>& candidates);

class JsonObject {
 public:
  /// `path` is the JSON path of `j` for messages ("" for the root, "solver", "fluid[1]").
  JsonObject(const nlohmann::json& j, std::string path);

  /// Ok when `j` is an object; otherwise an error naming the path.
  Status check_object() const;
  bool has(std::string_view key) const;
  const std::string& path() const { return path_; }
  std::string path_of(std::string_view key) const;

  // Each get: absent key → value untouched, success; wrong type → Param error naming the path.
  Status get(std::string_view key, float& out);
  Status get(std::string_view key, double& out);
  Status get(std::string_view key, int& out);
  Status get(std::string_view key, std::int64_t& out);
  Status get(std::string_view key, bool& out);
  Status get(std::string_view key, std::string& out);
  /// An array of 3 numbers, or (when `allow_scalar`) one number used for all three.
  Status get(std::string_view key, Vec3f& out, bool allow_scalar = false);
  /// The raw sub-value (marks the key as known); nullptr when absent.
  const nlohmann::json* child(std::string_view key);

  /// Declares keys that are valid here though not read through get() (e.g. a discriminator).
  void allow(std::initializer_list<std::string_view> keys);
  /// Error for the first key that was never read or allowed, with the closest valid key.
  Status finish() const;

 private:
  const nlohmann::json& j_;
  std::string path_;
  std::vector<std::string> known_;
};

}  // namespace ff::io
