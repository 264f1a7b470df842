#pragma once
// Scene JSON ↔ parameter structs through their one field list (core/fields.h): the reader takes every key the
// list names (types checked, enums by name, paths resolved against the scene's folder, nested objects and lists
// of objects), refuses the rest with the closest valid key, and the writer writes every field back, so that
// write → read gives the same struct (scene_io_test checks it for a whole scene).
#include "core/error.h"
#include "core/fields.h"
#include "core/printable.h"
#include "io/json_reader.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace ff::scene {

template <core::HasFields P>
Status read_object(const nlohmann::json& j, const std::string& path, P& params, const std::filesystem::path& base);

/// Reads every field of P that `o` holds into `params` (absent keys keep their values; required ones must be
/// there). The keys are marked as known, so o.finish() refuses only keys the list does not name.
template <core::HasFields P>
Status read_fields(io::JsonObject& o, P& params, const std::filesystem::path& base) {
  Status st;
  P::fields(params, [&](std::string_view key, auto& v, const core::FieldInfo& info) {
    using T = std::remove_cvref_t<decltype(v)>;
    if (!st.ok()) return;
    if (info.required && !o.has(key)) {
      st = param_error(fmt::format("{}: \"{}\" is required", o.path().empty() ? "scene" : o.path(), key));
      return;
    }
    if constexpr (core::HasFields<T>) {
      if (const nlohmann::json* c = o.child(key)) st = read_object(*c, o.path_of(key), v, base);
    } else if constexpr (core::IsFieldList<T>::value) {
      const nlohmann::json* c = o.child(key);
      if (!c) return;
      if (!c->is_array()) {
        st = param_error(fmt::format("{}: expected a list, got {}", o.path_of(key), c->type_name()));
        return;
      }
      v.clear();
      for (std::size_t i = 0; i < c->size() && st.ok(); ++i) {
        typename T::value_type item{};
        st = read_object((*c)[i], fmt::format("{}[{}]", o.path_of(key), i), item, base);
        if (st.ok()) v.push_back(std::move(item));
      }
    } else if constexpr (core::FieldEnum<T>) {
      std::string name(core::choice_name(v));
      st = o.get(key, name);
      if (!st.ok()) return;
      const std::optional<T> e = core::find_choice<T>(name);
      if (!e)
        st = param_error(fmt::format("{} = \"{}\" is not one of: {}", o.path_of(key), printable(name), core::choice_names(v)));
      else v = *e;
    } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
      std::string s;
      st = o.get(key, s);
      if (st.ok() && o.has(key)) {
        if (s.empty()) st = param_error(fmt::format("{}: a file is required", o.path_of(key)));
        else v = std::filesystem::path(s).is_absolute() ? std::filesystem::path(s) : base / s;
      }
    } else if constexpr (std::is_same_v<T, Vec3f>) {
      st = o.get(key, v, info.scalar_ok);
    } else if constexpr (std::is_same_v<T, std::size_t> || std::is_same_v<T, std::uint64_t>) {
      std::int64_t n = v > std::uint64_t(std::numeric_limits<std::int64_t>::max())
                           ? std::numeric_limits<std::int64_t>::max() : static_cast<std::int64_t>(v);
      st = o.get(key, n);
      if (st.ok() && n < 0) st = param_error(fmt::format("{} = {} must not be negative", o.path_of(key), n));
      else if (st.ok()) v = static_cast<T>(n);
    } else {
      st = o.get(key, v);  // float, double, int, bool, std::string
    }
  });
  return st;
}

/// `j` as an object at `path` holding P's fields and nothing else.
template <core::HasFields P>
Status read_object(const nlohmann::json& j, const std::string& path, P& params, const std::filesystem::path& base) {
  io::JsonObject o(j, path);
  FF_CHECK(o.check_object());
  FF_CHECK(read_fields(o, params, base));
  return o.finish();
}

/// Every field of `params` as JSON (paths absolute, so the scene reads the same from any folder).
template <core::HasFields P>
nlohmann::json fields_to_json(const P& params) {
  nlohmann::json j = nlohmann::json::object();
  P::fields(params, [&](std::string_view key, const auto& v, const core::FieldInfo&) {
    using T = std::remove_cvref_t<decltype(v)>;
    const std::string k(key);
    if constexpr (core::HasFields<T>) {
      j[k] = fields_to_json(v);
    } else if constexpr (core::IsFieldList<T>::value) {
      j[k] = nlohmann::json::array();
      for (const auto& item : v) j[k].push_back(fields_to_json(item));
    } else if constexpr (core::FieldEnum<T>) {
      j[k] = std::string(core::choice_name(v));
    } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
      j[k] = v.empty() ? std::string() : std::filesystem::absolute(v).lexically_normal().string();
    } else if constexpr (std::is_same_v<T, Vec3f>) {
      j[k] = nlohmann::json::array({v.x(), v.y(), v.z()});
    } else {
      j[k] = v;
    }
  });
  return j;
}

}  // namespace ff::scene
