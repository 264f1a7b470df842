#include "server/messages.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace ff::server {
using nlohmann::json;

namespace {
Result<Vec3f> vec3(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_array() || it->size() != 3) return input_error(std::string(key) + " must be [x, y, z]");
  Vec3f v;
  for (int a = 0; a < 3; ++a) {
    const auto& e = (*it)[std::size_t(a)];
    if (!e.is_number() || !std::isfinite(e.get<double>()) || std::abs(e.get<double>()) > 1e6)
      return input_error(std::string(key) + " must hold three finite numbers");
    v[a] = e.get<float>();
  }
  return v;
}

Result<std::size_t> index(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_unsigned() || it->get<std::uint64_t>() > 1'000'000)
    return input_error(std::string(key) + " must be a small non-negative integer");
  return static_cast<std::size_t>(it->get<std::uint64_t>());
}
}  // namespace

Result<Command> parse_command(std::string_view text) {
  if (text.size() > kMaxClientMessage) return input_error("message too long");
  const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return input_error("not a JSON object");
  const auto type = j.find("type");
  if (type == j.end() || !type->is_string()) return input_error("no \"type\"");
  const std::string t = type->get<std::string>();
  Command c;
  if (t == "play") c.kind = Command::Kind::Play;
  else if (t == "pause") c.kind = Command::Kind::Pause;
  else if (t == "restart") c.kind = Command::Kind::Restart;
  else if (t == "controller") {
    c.kind = Command::Kind::Controller;
    const auto n = j.find("name");
    if (n == j.end() || !n->is_string() || n->get<std::string>().size() > 64) return input_error("controller: no name");
    c.name = n->get<std::string>();
  } else if (t == "pose") {
    c.kind = Command::Kind::Pose;
    FF_TRY(c.target, index(j, "target"));
    FF_TRY(c.pose.translate, vec3(j, "translate"));
    if (j.contains("rotate")) {
      FF_TRY(c.pose.rotate_deg, vec3(j, "rotate"));
    }
    if (j.contains("scale")) {
      const auto& s = j["scale"];
      if (!s.is_number() || !(s.get<double>() > 0.0) || !(s.get<double>() < 1e3)) return input_error("scale must be in (0, 1000)");
      c.pose.scale = s.get<float>();
    }
  } else if (t == "mesh") {
    c.kind = Command::Kind::Mesh;
    FF_TRY(c.target, index(j, "target"));
    FF_TRY(c.mesh, index(j, "mesh"));
  } else if (t == "surface") {
    c.kind = Command::Kind::Surface;
    const auto on = j.find("on");
    if (on == j.end() || !on->is_boolean()) return input_error("surface: \"on\" must be true or false");
    c.on = on->get<bool>();
  } else if (t == "seek") {
    c.kind = Command::Kind::Seek;
    FF_TRY(c.frame, index(j, "frame"));
  } else {
    return input_error("unknown type");
  }
  return c;
}

}  // namespace ff::server
