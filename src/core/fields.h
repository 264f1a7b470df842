#pragma once
// One field list per parameter struct. A struct P describes its fields once:
//
//   template <class S, class F> static void fields(S& self, F&& f) {   // S = P or const P
//     f("particle_radius", self.particle_radius, core::open_closed(1e-4, 10.0, "r, m; spacing d = 2r"));
//     f("method", self.method, core::choice("sampler"));                // an enum with field_choices(E)
//     f("sparse", self.sparse, core::nested("samples dropped on purpose"));  // a struct with its own fields()
//   }
//
// and that one list drives everything that must name each field: validate_fields() here (ranges, NaN), the
// scene reader and writer (scene/fields_json.h: unknown keys with the closest valid key, types, round trip), and
// the table of scene keys in `fluidform keys` and docs/scene-keys.md. A field type is one of: float, double, int,
// std::size_t, std::uint64_t, bool, std::string, std::filesystem::path, Vec3f, an enum E (with an ADL function
// `field_choices(E)` returning its names), a struct with fields(), or a std::vector of such a struct.
// Cross-field rules (max_iterations ≥ iterations, a box's min < max) stay in the struct's validate(), after
// validate_fields().
#include "core/error.h"
#include "core/params.h"
#include "core/types.h"

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace ff::core {

/// What a field list says of one field besides its key and its value.
struct FieldInfo {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  Bound lb = Bound::Closed, hb = Bound::Closed;
  std::string_view doc;      ///< one line for the key table (units first)
  bool required = false;     ///< the scene must give it (no usable default)
  bool scalar_ok = false;    ///< a Vec3f that may also be given as one number for all three (a uniform scale)
  bool either_sign = false;  ///< a Vec3f whose components' magnitudes lie in the range, of either sign (a mirror)
  bool ranged() const { return lo > -std::numeric_limits<double>::infinity() || hi < std::numeric_limits<double>::infinity(); }
};

constexpr FieldInfo closed(double lo, double hi, std::string_view doc) { return {lo, hi, Bound::Closed, Bound::Closed, doc}; }
constexpr FieldInfo open_closed(double lo, double hi, std::string_view doc) { return {lo, hi, Bound::Open, Bound::Closed, doc}; }
constexpr FieldInfo closed_open(double lo, double hi, std::string_view doc) { return {lo, hi, Bound::Closed, Bound::Open, doc}; }
constexpr FieldInfo open(double lo, double hi, std::string_view doc) { return {lo, hi, Bound::Open, Bound::Open, doc}; }
/// A field without a range: a flag, a string, an enum, a nested struct or list.
constexpr FieldInfo plain(std::string_view doc) { FieldInfo i; i.doc = doc; return i; }
constexpr FieldInfo required(FieldInfo i) { i.required = true; return i; }
constexpr FieldInfo scalar_ok(FieldInfo i) { i.scalar_ok = true; return i; }
constexpr FieldInfo either_sign(FieldInfo i) { i.either_sign = true; return i; }

/// An enum value and its name in scene files.
template <class E>
struct Choice {
  E value;
  std::string_view name;
};

template <class T>
concept HasFields = requires(T& t) { T::fields(t, [](std::string_view, auto&, const FieldInfo&) {}); };
template <class T>
concept FieldEnum = std::is_enum_v<T> && requires(T e) { field_choices(e); };

template <class T>
struct IsFieldList : std::false_type {};
template <class T>
struct IsFieldList<std::vector<T>> : std::bool_constant<HasFields<T>> {};

/// The name of an enum value ("?" when it has none).
template <FieldEnum E>
std::string_view choice_name(E e) {
  for (const auto& c : field_choices(e))
    if (c.value == e) return c.name;
  return "?";
}
/// "a, b, c" for messages and the key table.
template <FieldEnum E>
std::string choice_names(E e) {
  std::string s;
  for (const auto& c : field_choices(e)) s += (s.empty() ? "" : ", ") + std::string(c.name);
  return s;
}
/// The value named `name`, if there is one.
template <FieldEnum E>
std::optional<E> find_choice(std::string_view name, E e = {}) {
  for (const auto& c : field_choices(e))
    if (c.name == name) return c.value;
  return std::nullopt;
}

/// Every field of `params` against its range (NaN fails every range), nested structs and lists included; the
/// first violation names `path.key`, the value and the range.
template <HasFields P>
Status validate_fields(const P& params, std::string_view path) {
  Status st;
  P::fields(params, [&](std::string_view key, const auto& v, const FieldInfo& info) {
    using T = std::remove_cvref_t<decltype(v)>;
    if (!st.ok()) return;
    if constexpr (HasFields<T>) {
      st = validate_fields(v, fmt::format("{}.{}", path, key));
    } else if constexpr (IsFieldList<T>::value) {
      for (std::size_t i = 0; i < v.size() && st.ok(); ++i) st = validate_fields(v[i], fmt::format("{}.{}[{}]", path, key, i));
    } else if constexpr (std::is_same_v<T, Vec3f>) {
      if (info.ranged()) st = check_vec(path, key, v, info.lo, info.hi, info.either_sign);
    } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      if (info.ranged()) st = check_range(path, key, static_cast<double>(v), info.lo, info.hi, info.lb, info.hb);
    }
  });
  return st;
}

/// One row of the scene-key table: "solver.particle_radius", "number", "0.025", "(0.0001, 10]", the doc line.
struct KeyRow {
  std::string key, type, default_value, range, doc;
};

namespace detail {
inline std::string format_value(double v) { return fmt::format("{:g}", v); }
}  // namespace detail

/// The rows of every field of P (defaults from a default-constructed P), keys prefixed with `path.`.
template <HasFields P>
void key_rows(std::string_view path, std::vector<KeyRow>& rows, const P& defaults = P{}) {
  P::fields(defaults, [&](std::string_view key, const auto& v, const FieldInfo& info) {
    using T = std::remove_cvref_t<decltype(v)>;
    const std::string k = path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
    KeyRow r{k, "", "", info.ranged() ? (info.either_sign ? "±" : "") + format_range(info.lo, info.hi, info.lb, info.hb) : "",
             std::string(info.doc)};
    if (info.required) r.default_value = "required";
    if constexpr (HasFields<T>) {
      key_rows(k, rows, v);
      return;
    } else if constexpr (IsFieldList<T>::value) {
      rows.push_back({k, "list", "[]", "", std::string(info.doc)});
      key_rows<typename T::value_type>(k + "[]", rows);
      return;
    } else if constexpr (std::is_same_v<T, bool>) {
      r.type = "bool", r.default_value = v ? "true" : "false";
    } else if constexpr (FieldEnum<T>) {
      r.type = "string", r.default_value = fmt::format("\"{}\"", choice_name(v)), r.range = choice_names(v);
    } else if constexpr (std::is_same_v<T, Vec3f>) {
      r.type = info.scalar_ok ? "number or [x, y, z]" : "[x, y, z]";
      if (!info.required) r.default_value = fmt::format("[{:g}, {:g}, {:g}]", v.x(), v.y(), v.z());
    } else if constexpr (std::is_same_v<T, std::string>) {
      r.type = "string";
      if (!info.required) r.default_value = fmt::format("\"{}\"", v);
    } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
      r.type = "path";
      if (!info.required) r.default_value = fmt::format("\"{}\"", v.string());
    } else {
      r.type = std::is_integral_v<T> ? "integer" : "number";
      if (!info.required) r.default_value = detail::format_value(static_cast<double>(v));
    }
    rows.push_back(std::move(r));
  });
}

}  // namespace ff::core
