#include "io/json_reader.h"

#include "core/printable.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ff::io {
using nlohmann::json;

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    prev.swap(cur);
  }
  return prev[b.size()];
}

std::string closest_key(std::string_view key, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(key, c);
    if (d < best_d) best_d = d, best = c;
  }
  // A typo, not a different word: at most a third of the key (and at least 2 edits) away.
  return best_d <= std::max<std::size_t>(2, key.size() / 3) ? best : std::string();
}

JsonObject::JsonObject(const json& j, std::string path) : j_(j), path_(std::move(path)) {}

Status JsonObject::check_object() const {
  if (j_.is_object()) return {};
  return param_error(fmt::format("{}: expected a JSON object, got {}", path_.empty() ? "scene" : path_, j_.type_name()));
}

bool JsonObject::has(std::string_view key) const { return j_.is_object() && j_.contains(key); }

std::string JsonObject::path_of(std::string_view key) const {
  // A key is any JSON string: one with a newline or a control character must not break the message's line.
  return path_.empty() ? printable(key) : fmt::format("{}.{}", path_, printable(key));
}

const json* JsonObject::child(std::string_view key) {
  known_.emplace_back(key);
  if (!has(key)) return nullptr;
  return &j_.at(std::string(key));
}

namespace {
Status type_error(const std::string& path, std::string_view want, const json& v) {
  std::string shown = v.dump();  // JSON escapes control characters, except DEL
  if (shown.size() > 40) shown = shown.substr(0, 37) + "...";
  return param_error(fmt::format("{}: expected {}, got {}", path, want, printable(shown)));
}
}  // namespace

Status JsonObject::get(std::string_view key, double& out) {
  const json* v = child(key);
  if (!v) return {};
  if (!v->is_number()) return type_error(path_of(key), "a number", *v);
  out = v->get<double>();
  return {};
}

Status JsonObject::get(std::string_view key, float& out) {
  double d = out;
  FF_CHECK(get(key, d));
  if (std::isfinite(d) && std::abs(d) > double(std::numeric_limits<float>::max()))
    return param_error(fmt::format("{} = {} is too large", path_of(key), d));
  out = static_cast<float>(d);
  return {};
}

Status JsonObject::get(std::string_view key, std::int64_t& out) {
  const json* v = child(key);
  if (!v) return {};
  if (v->is_number_integer()) {
    out = v->get<std::int64_t>();
    return {};
  }
  if (v->is_number_float()) {
    const double d = v->get<double>();
    if (d == std::floor(d) && std::abs(d) < 9e15) {
      out = static_cast<std::int64_t>(d);
      return {};
    }
  }
  return type_error(path_of(key), "an integer", *v);
}

Status JsonObject::get(std::string_view key, int& out) {
  std::int64_t v = out;
  FF_CHECK(get(key, v));
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    return param_error(fmt::format("{} = {} is too large", path_of(key), v));
  out = static_cast<int>(v);
  return {};
}

Status JsonObject::get(std::string_view key, bool& out) {
  const json* v = child(key);
  if (!v) return {};
  if (!v->is_boolean()) return type_error(path_of(key), "true or false", *v);
  out = v->get<bool>();
  return {};
}

Status JsonObject::get(std::string_view key, std::string& out) {
  const json* v = child(key);
  if (!v) return {};
  if (!v->is_string()) return type_error(path_of(key), "a string", *v);
  out = v->get<std::string>();
  return {};
}

Status JsonObject::get(std::string_view key, Vec3f& out, bool allow_scalar) {
  const json* v = child(key);
  if (!v) return {};
  if (allow_scalar && v->is_number()) {
    out = Vec3f::Constant(v->get<float>());
    return {};
  }
  if (!v->is_array() || v->size() != 3 || !(*v)[0].is_number() || !(*v)[1].is_number() || !(*v)[2].is_number())
    return type_error(path_of(key), allow_scalar ? "a number or an array of 3 numbers" : "an array of 3 numbers", *v);
  out = Vec3f((*v)[0].get<float>(), (*v)[1].get<float>(), (*v)[2].get<float>());
  return {};
}

void JsonObject::allow(std::initializer_list<std::string_view> keys) {
  for (auto k : keys) known_.emplace_back(k);
}

Status JsonObject::finish() const {
  if (!j_.is_object()) return {};
  for (const auto& [key, value] : j_.items()) {
    if (std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
    const std::string near = closest_key(key, known_);
    if (!near.empty())
      return param_error(fmt::format("{}: unknown key (did you mean '{}'?)", path_of(key), near));
    std::string valid;
    for (const auto& k : known_) valid += (valid.empty() ? "" : ", ") + k;
    return param_error(fmt::format("{}: unknown key (valid keys here: {})", path_of(key), valid));
  }
  return {};
}

}  // namespace ff::io
