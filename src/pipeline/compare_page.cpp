#include "pipeline/compare_page.h"

#include "io/atomic_file.h"

#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <vector>

namespace ff::pipeline {
namespace fs = std::filesystem;

namespace {

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) o += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : c == '"' ? "&quot;" : std::string(1, c);
  return o;
}

// A PNG file as an inline image, or "" when there is none.
std::string inline_png(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return "";
  const std::vector<std::uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return b.empty() ? "" : "data:image/png;base64," + base64(b.data(), b.size());
}

// Click a column's head to sort by it (numbers as numbers, "n/a" and failures last), again to reverse.
constexpr const char* kSortScript = R"(
for (const th of document.querySelectorAll('#table th[data-col]')) {
  th.addEventListener('click', () => {
    const body = document.querySelector('#table tbody'), col = Number(th.dataset.col);
    const up = th.dataset.dir !== 'up';
    document.querySelectorAll('#table th').forEach((h) => { delete h.dataset.dir; });
    th.dataset.dir = up ? 'up' : 'down';
    const key = (tr) => { const t = tr.children[col].textContent.trim(); const v = parseFloat(t); return Number.isNaN(v) ? t : v; };
    const rows = [...body.rows].sort((a, b) => {
      const x = key(a), y = key(b), xn = typeof x === 'number', yn = typeof y === 'number';
      if (xn !== yn) return xn ? -1 : 1;
      const c = xn ? x - y : String(x).localeCompare(String(y));
      return up ? c : -c;
    });
    body.append(...rows);
  });
}
document.body.dataset.ready = '1';
)";

constexpr const char* kStyle = R"(
body { font: 14px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1280px; padding: 16px 24px 48px; color: #1d2430; }
h1 { font-size: 20px; margin: 8px 0 4px; } .sub { color: #5a6575; margin: 0 0 16px; }
table { border-collapse: collapse; } th, td { padding: 4px 10px; text-align: right; vertical-align: middle; }
th { border-bottom: 1px solid #ccd3dc; cursor: pointer; user-select: none; } th:first-child, td:first-child { text-align: left; }
th[data-dir=up]::after { content: ' ▲'; } th[data-dir=down]::after { content: ' ▼'; }
tr.failure td { color: #a3261b; } tr.failure td.status { font-weight: 600; }
td img { width: 150px; border-radius: 4px; display: block; } .target img { width: 220px; border-radius: 6px; }
)";

std::string row_html(const fs::path& out_dir, const CompareRow& r) {
  std::string s = fmt::format("<tr class=\"{}\">", r.ok ? "ok" : "failure");
  const auto cells = markdown_cells(r);
  for (std::size_t c = 0; c < cells.size(); ++c)
    s += fmt::format("<td{}>{}</td>", c + 1 == cells.size() ? " class=\"status\"" : "", escape(cells[c]));
  const std::string png = inline_png(out_dir / r.controller / "formed.png");
  s += png.empty() ? "<td>no mesh</td>" : fmt::format("<td><img src=\"{}\" alt=\"{} formed\"></td>", png, escape(r.controller));
  s += fs::exists(out_dir / r.controller / "report.html")
           ? fmt::format("<td><a href=\"{0}/report.html\">{0}</a></td>", escape(r.controller))
           : "<td>–</td>";
  return s + "</tr>\n";
}

}  // namespace

std::string base64(const std::uint8_t* p, std::size_t n) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  s.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const std::uint32_t v = (std::uint32_t(p[i]) << 16) | (i + 1 < n ? std::uint32_t(p[i + 1]) << 8 : 0u) |
                            (i + 2 < n ? std::uint32_t(p[i + 2]) : 0u);
    s += kDigits[(v >> 18) & 63];
    s += kDigits[(v >> 12) & 63];
    s += i + 1 < n ? kDigits[(v >> 6) & 63] : '=';
    s += i + 2 < n ? kDigits[v & 63] : '=';
  }
  return s;
}

io::PictureView compare_view(const io::TriangleMesh& targets) {
  io::PictureView v;
  for (const Vec3f& p : targets.vertices) v.box.extend(p);
  if (!v.box.empty()) {
    const Vec3f pad = 0.125f * (v.box.max - v.box.min);
    v.box.min -= pad, v.box.max += pad;
  }
  v.width = v.height = 300;
  return v;
}

Status write_still(const fs::path& png, const io::TriangleMesh& mesh, const io::PictureView& view, bool target) {
  FF_TRY(const auto bytes, io::encode_png(io::render_mesh(mesh, target ? kTargetColour : kLiquidColour, view)));
  return io::write_file_atomic(png, std::span<const std::uint8_t>(bytes));
}

Status write_compare_page(const fs::path& out_dir, const CompareTable& t) {
  std::string h = "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<link rel=\"icon\" href=\"data:,\">\n";
  h += fmt::format("<title>fluidform compare: {}</title>\n<style>{}</style>\n</head>\n<body>\n", escape(t.scene), kStyle);
  h += fmt::format("<h1>fluidform compare: {}</h1>\n<p class=\"sub\">{} ({} particles, {} frames, {:.2f} s simulated, {} "
                   "threads, {}{}). The paper's Table 3 columns; click a column to sort by it. Failures are marked as in "
                   "the paper.</p>\n",
                   escape(t.scene), escape(t.scene_file), std::isfinite(t.particles) ? fmt::format("{:.0f}", t.particles) : "n/a",
                   t.frames, t.frames / t.fps, t.threads, escape(t.cpu), t.device == "cpu" ? "" : ", --device " + escape(t.device));
  if (const std::string target = inline_png(out_dir / "target.png"); !target.empty())
    h += fmt::format("<figure class=\"target\"><img src=\"{}\" alt=\"target\"><figcaption>target</figcaption></figure>\n", target);
  h += "<table id=\"table\">\n<thead><tr>";
  const auto& cols = markdown_columns();
  for (std::size_t c = 0; c < cols.size(); ++c) h += fmt::format("<th data-col=\"{}\">{}</th>", c, escape(cols[c]));
  h += "<th>formed shape</th><th>report</th></tr></thead>\n<tbody>\n";
  bool any_approx = false;
  for (const auto& r : t.rows) h += row_html(out_dir, r), any_approx = any_approx || r.approximation;
  h += "</tbody>\n</table>\n";
  if (any_approx) h += "<p class=\"sub\">[A]: an approximation of a method whose details are not public.</p>\n";
  h += fmt::format("<script>{}</script>\n</body>\n</html>\n", kSortScript);
  return io::write_file_atomic(out_dir / "compare.html", h);
}

}  // namespace ff::pipeline
