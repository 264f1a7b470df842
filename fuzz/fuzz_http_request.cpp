// The live viewer's HTTP request path (server/ws_server.cpp HttpSession, server/static_files.h): any bytes as what a
// client sends on a connection, parsed by Beast's request parser with the server's limits (pipelined requests one
// after the other), each GET/HEAD target resolved against mounts like `serve`'s ("/" and "/vendor/three/") in a
// scratch folder that also holds a file outside them and symlinks out of them. The same bytes are also resolved as
// a bare request target. Whatever the path, the answer is one of 200/400/403/404, and a 200 is a regular file inside
// its mount, never the file outside.
#include "fuzz_target.h"
#include "server/static_files.h"

#include <boost/asio/buffer.hpp>
#include <boost/beast/core/error.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket/rfc6455.hpp>

#include <algorithm>
#include <fstream>
#include <optional>
#include <unistd.h>

namespace {
namespace fs = std::filesystem;
namespace http = boost::beast::http;

struct Site {
  fs::path base, web, three;
  std::optional<ff::server::StaticFiles> files;
  Site() {
    std::error_code ec;
    base = fs::temp_directory_path(ec) / ("fluidform-fuzz-http-" + std::to_string(::getpid()));
    web = base / "web";
    three = base / "three";
    fs::remove_all(base, ec);
    fs::create_directories(web / "src", ec);
    fs::create_directories(three / "build", ec);
    std::ofstream(web / "index.html") << "<html>";
    std::ofstream(web / "src" / "main.js") << "x";
    std::ofstream(three / "build" / "three.module.js") << "y";
    std::ofstream(base / "secret.txt") << "secret";
    fs::create_symlink(base / "secret.txt", web / "link.txt", ec);
    fs::create_directory_symlink(base, web / "up", ec);
    files.emplace(std::vector<ff::server::Mount>{{"/", web}, {"/vendor/three/", three}});
    web = fs::canonical(web, ec);
    three = fs::canonical(three, ec);
  }
  ~Site() {
    std::error_code ec;
    fs::remove_all(base, ec);
  }
};

const Site& site() {
  static const Site s;
  return s;
}

bool inside(const fs::path& file, const fs::path& dir) {
  auto [d, f] = std::mismatch(dir.begin(), dir.end(), file.begin(), file.end());
  return d == dir.end();
}

void resolve(std::string_view target) {
  const Site& s = site();
  const auto r = s.files->resolve(target);
  FF_FUZZ_CHECK(r.status == 200 || r.status == 400 || r.status == 403 || r.status == 404);
  if (r.status != 200) return;
  std::error_code ec;
  FF_FUZZ_CHECK(fs::is_regular_file(r.file, ec));
  FF_FUZZ_CHECK(inside(r.file, s.web) || inside(r.file, s.three));
  FF_FUZZ_CHECK(r.file.filename() != "secret.txt");
  FF_FUZZ_CHECK(!r.mime.empty());
}
}  // namespace

FF_FUZZ_TARGET(http_request) {
  resolve(ff::fuzz::as_text(data, size));
  std::size_t used = 0;
  for (int k = 0; k < 8 && used < size; ++k) {  // pipelined requests on one connection
    http::request_parser<http::string_body> parser;
    parser.header_limit(16 * 1024);  // as HttpSession::read
    parser.body_limit(16 * 1024);
    boost::beast::error_code ec;
    while (!parser.is_done()) {
      const std::size_t n = parser.put(boost::asio::buffer(data + used, size - used), ec);
      used += n;
      if (ec == http::error::need_more) {  // all the bytes there are: the connection ends
        ec = {};
        parser.put_eof(ec);
        break;
      }
      if (ec || n == 0) break;
    }
    if (ec || !parser.is_done()) return 0;  // the server drops the connection
    const auto& req = parser.get();
    if (boost::beast::websocket::is_upgrade(req)) continue;  // /ws or 404, no file
    if (req.method() != http::verb::get && req.method() != http::verb::head) continue;  // 405
    resolve(std::string_view(req.target().data(), req.target().size()));
  }
  return 0;
}
