#include "io/write_ply.h"

#include "core/printable.h"
#include "io/atomic_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace ff::io {

static_assert(std::endian::native == std::endian::little, "PLY writer assumes a little-endian host");

std::vector<std::uint8_t> encode_particles_ply(const ParticleFrameView& f) {
  const std::size_t n = f.positions.size();
  const bool vel = !f.velocities.empty(), tgt = !f.targets.empty();
  std::string comments;
  for (std::size_t b = 0; b <= f.comment.size();) {
    std::size_t e = f.comment.find('\n', b);
    if (e == std::string_view::npos) e = f.comment.size();
    comments += fmt::format("comment {}\n", f.comment.substr(b, e - b));
    b = e + 1;
  }
  std::string header = fmt::format("ply\nformat binary_little_endian 1.0\n{}"
                                   "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
                                   comments, n);
  if (vel) header += "property float vx\nproperty float vy\nproperty float vz\n";
  if (tgt) header += "property uchar target\n";
  for (const auto& s : f.scalars) header += fmt::format("property float {}\n", s.name);
  header += "end_header\n";
  const std::size_t stride = 12 + (vel ? 12 : 0) + (tgt ? 1 : 0) + 4 * f.scalars.size();
  std::vector<std::uint8_t> out(header.size() + n * stride);
  std::memcpy(out.data(), header.data(), header.size());
  std::uint8_t* p = out.data() + header.size();
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(p, f.positions[i].data(), 12);
    p += 12;
    if (vel) {
      std::memcpy(p, f.velocities[i].data(), 12);
      p += 12;
    }
    if (tgt) *p++ = f.targets[i];
    for (const auto& s : f.scalars) {
      std::memcpy(p, &s.values[i], 4);
      p += 4;
    }
  }
  return out;
}

Status write_particles_ply(const std::filesystem::path& path, const ParticleFrameView& frame) {
  if (!frame.velocities.empty() && frame.velocities.size() != frame.positions.size())
    return input_error("write_particles_ply: velocity count differs from position count");
  if (!frame.targets.empty() && frame.targets.size() != frame.positions.size())
    return input_error("write_particles_ply: target count differs from position count");
  for (const auto& s : frame.scalars) {
    if (s.values.size() != frame.positions.size())
      return input_error(fmt::format("write_particles_ply: property '{}' count differs from position count", s.name));
    const bool name_ok = !s.name.empty() && std::all_of(s.name.begin(), s.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
    });
    if (!name_ok) return input_error(fmt::format("write_particles_ply: bad property name '{}'", s.name));
  }
  const auto bytes = encode_particles_ply(frame);
  return write_file_atomic(path, bytes);
}

namespace {
/// A particle PLY's header: the vertex count, its properties (name, bytes) and comments.
struct PlyHeader {
  struct Prop { std::string name; int size; };
  std::size_t n = 0;
  std::vector<Prop> props;
  std::vector<std::string> comments;
};

/// Where a record holds x y z, vx vy vz (−1: absent) and the target byte (−1: absent), and its size.
struct PlyLayout {
  int ix = -1, ivx = -1, itg = -1;
  std::size_t stride = 0;
};

/// The header up to end_header; a particle PLY is binary little-endian with one vertex element.
Result<PlyHeader> read_header(std::istream& in, std::string_view file) {
  std::string line;
  std::getline(in, line);
  if (line != "ply") return input_error(fmt::format("{}: not a PLY file", file));
  PlyHeader h;
  bool in_vertex = false, binary_le = false;
  while (std::getline(in, line)) {
    if (line == "end_header") break;
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "comment") {
      h.comments.push_back(line.size() > 8 ? line.substr(8) : std::string());
    } else if (word == "format") {
      std::string fmt_name;
      ls >> fmt_name;
      binary_le = fmt_name == "binary_little_endian";
    } else if (word == "element") {
      std::string name;
      ls >> name;
      in_vertex = name == "vertex";
      if (in_vertex) ls >> h.n;
      else return input_error(fmt::format("{}: unexpected element '{}' in a particle PLY", file, printable(name)));
    } else if (word == "property" && in_vertex) {
      std::string type, name;
      ls >> type >> name;
      if (type == "float" || type == "float32") h.props.push_back({name, 4});
      else if (type == "uchar" || type == "uint8") h.props.push_back({name, 1});
      else return input_error(fmt::format("{}: unsupported property type '{}'", file, printable(type)));
    }
  }
  if (!binary_le) return input_error(fmt::format("{}: particle PLY must be binary_little_endian", file));
  return h;
}

/// The record layout of `props`: x y z (and vx vy vz) must be consecutive floats, as written by write_particles_ply.
Result<PlyLayout> record_layout(const std::vector<PlyHeader::Prop>& props, std::string_view file) {
  PlyLayout l;
  int off = 0;
  std::size_t kx = props.size(), kvx = props.size();
  for (std::size_t k = 0; k < props.size(); ++k) {
    const auto& p = props[k];
    if (p.name == "x") l.ix = off, kx = k;
    if (p.name == "vx") l.ivx = off, kvx = k;
    if (p.name == "target") l.itg = off;
    if (p.name == "target" && p.size != 1) return input_error(fmt::format("{}: property 'target' must be a uchar", file));
    off += p.size;
  }
  // Each triple is read as one.
  const auto float_triple = [&](std::size_t k, const char* a, const char* b, const char* c) {
    return k + 2 < props.size() && props[k].name == a && props[k + 1].name == b && props[k + 2].name == c &&
           props[k].size == 4 && props[k + 1].size == 4 && props[k + 2].size == 4;
  };
  if (l.ix < 0) return input_error(fmt::format("{}: no x y z properties", file));
  if (!float_triple(kx, "x", "y", "z"))
    return input_error(fmt::format("{}: x y z must be three consecutive float properties", file));
  if (l.ivx >= 0 && !float_triple(kvx, "vx", "vy", "vz"))
    return input_error(fmt::format("{}: vx vy vz must be three consecutive float properties", file));
  l.stride = static_cast<std::size_t>(off);
  return l;
}

/// The n records of `buf` unpacked; every other float property is kept by name.
ParticleFrame unpack_records(const std::vector<char>& buf, PlyHeader& h, const PlyLayout& l) {
  const std::size_t n = h.n, stride = l.stride;
  const int ix = l.ix, ivx = l.ivx, itg = l.itg;
  ParticleFrame f;
  f.comments = std::move(h.comments);
  f.positions.resize(n);
  if (ivx >= 0) f.velocities.resize(n);
  if (itg >= 0) f.targets.resize(n);
  std::vector<int> scalar_offset;
  {
    int o = 0;
    for (const auto& p : h.props) {
      const bool known = p.name == "x" || p.name == "y" || p.name == "z" || p.name == "target" ||
                         (ivx >= 0 && (p.name == "vx" || p.name == "vy" || p.name == "vz"));
      if (!known && p.size == 4) {
        f.scalars.emplace_back(p.name, std::vector<float>(n));
        scalar_offset.push_back(o);
      }
      o += p.size;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const char* rec = buf.data() + i * stride;
    std::memcpy(f.positions[i].data(), rec + ix, 12);
    if (ivx >= 0) std::memcpy(f.velocities[i].data(), rec + ivx, 12);
    if (itg >= 0) f.targets[i] = static_cast<std::uint8_t>(rec[itg]);
    for (std::size_t s = 0; s < scalar_offset.size(); ++s)
      std::memcpy(&f.scalars[s].second[i], rec + scalar_offset[s], 4);
  }
  return f;
}

/// The reader behind read_particles_ply and decode_particles_ply; `file` stands for the file in messages.
Result<ParticleFrame> read_particles(std::istream& in, std::string_view file) {
  FF_TRY(PlyHeader h, read_header(in, file));
  FF_TRY(const PlyLayout layout, record_layout(h.props, file));
  const std::size_t n = h.n, stride = layout.stride;
  // A header may claim any count: check it against the file before allocating.
  const auto here = in.tellg();
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg() - here);
  in.seekg(here);
  if (stride == 0 || n > size / stride)
    return input_error(fmt::format("{}: truncated ({} bytes of particle data for {} particles of {} bytes)",
                                   file, size, n, stride));
  std::vector<char> buf(n * stride);
  in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
  if (static_cast<std::size_t>(in.gcount()) != buf.size())
    return input_error(fmt::format("{}: truncated ({} of {} bytes of particle data)", file, in.gcount(), buf.size()));
  return unpack_records(buf, h, layout);
}
}  // namespace

Result<ParticleFrame> read_particles_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot open", path.string()));
  return read_particles(in, path.string());
}

Result<ParticleFrame> decode_particles_ply(std::span<const std::uint8_t> bytes, std::string_view name) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()), std::ios::binary);
  return read_particles(in, name);
}

}  // namespace ff::io
