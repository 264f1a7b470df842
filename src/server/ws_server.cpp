#include "server/ws_server.h"

#include "server/static_files.h"

#if defined(__SANITIZE_THREAD__)
// ThreadSanitizer does not model the stand-alone fences of Asio's fenced blocks (gcc refuses them under -Wtsan); a
// handler already passes between threads under the scheduler's mutex, which it does see. This is the only file that
// includes Asio, so every user of it agrees.
#define BOOST_ASIO_DISABLE_FENCED_BLOCK
#endif
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <deque>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

namespace ff::server {
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Bytes = std::vector<std::uint8_t>;

Status ServerOptions::validate() const {
  if (max_clients < 1 || max_clients > 1000)
    return param_error(fmt::format("--max-clients = {} is outside [1, 1000]", max_clients));
  if (max_message < 256 || max_message > (1u << 24)) return param_error("max_message is outside [256, 16 MiB]");
  boost::system::error_code ec;
  (void)net::ip::make_address(bind, ec);
  if (ec) return param_error(fmt::format("--bind {}: not an IP address", bind));
  return {};
}

class WsSession;

struct WsServer::Impl {
  ServerOptions opt;
  const StaticFiles& files;
  Callbacks cb;
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  net::signal_set signals{ioc};
  std::thread thread;
  std::atomic<std::uint16_t> port{0};
  std::atomic<bool> stopped{false};
  // Touched on the I/O thread only.
  std::vector<std::weak_ptr<WsSession>> sessions;
  // Read from other threads.
  std::atomic<std::uint64_t> frames_sent{0}, frames_skipped{0}, bad_messages{0};
  std::atomic<int> clients{0};
  // The newest frame and surface published and not yet handed to the sessions. One handler at a time carries them
  // to the I/O thread: a publisher faster than that thread (it is starved, or busy with many clients) replaces them
  // here instead of queueing a handler, and a frame with it, per publish in the io_context.
  std::mutex slot_mu;
  std::shared_ptr<const Bytes> next_frame, next_surface;  // under slot_mu

  Impl(ServerOptions o, const StaticFiles& f, Callbacks c) : opt(std::move(o)), files(f), cb(std::move(c)) {}
  void accept();
  void hand_over(std::shared_ptr<const Bytes> Impl::*slot, std::shared_ptr<const Bytes> item, bool count_skipped,
                 void (WsSession::*queue)(std::shared_ptr<const Bytes>));
  int live_sessions() {
    std::erase_if(sessions, [](const auto& w) { return w.expired(); });
    return static_cast<int>(sessions.size());
  }
};

// One WebSocket client. Text messages out are queued (they are few and each matters: pose acknowledgements); binary
// frames are not: `pending_` holds only the newest, replaced whenever a newer one comes before the write of the
// previous one has finished. Live surfaces (much rarer, larger) have their own newest-only slot, `surface_`, so a
// particle frame never pushes out a surface nor the other way round.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket&& socket, WsServer::Impl& server) : ws_(std::move(socket)), server_(server) {}

  void run(http::request<http::string_body> req) {
    // Counted from the upgrade on, not from the end of the handshake: a burst of upgrades read before any handshake
    // has finished would otherwise each pass the max_clients check.
    server_.sessions.push_back(weak_from_this());
    server_.clients = server_.live_sessions();
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    // No limit in Beast itself (it would fail the connection with 1009): read() takes messages a piece at a time
    // and drops one that grows past max_message, so an oversized message is ignored and the client stays.
    ws_.read_message_max(0);
    ws_.auto_fragment(false);  // a frame goes out as one WebSocket frame: no per-4 KiB headers
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  void queue_frame(std::shared_ptr<const Bytes> frame) {
    if (pending_) server_.frames_skipped.fetch_add(1, std::memory_order_relaxed);
    pending_ = std::move(frame);
    write_next();
  }
  void queue_surface(std::shared_ptr<const Bytes> surface) {
    surface_ = std::move(surface);
    write_next();
  }
  void queue_text(std::shared_ptr<const std::string> text) {
    // Still in the handshake: its hello, sent first once open, already says whatever this would have told it.
    if (!open_) return;
    if (texts_.size() >= 256) return;  // a client that reads nothing must not grow the server's memory
    texts_.push_back(std::move(text));
    write_next();
  }
  void close() {
    if (!open_) return;
    open_ = false;
    ws_.async_close(websocket::close_code::going_away, [self = shared_from_this()](beast::error_code) {});
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec) return gone();
    open_ = true;
    if (server_.cb.hello) queue_text(std::make_shared<const std::string>(server_.cb.hello()));
    read();
  }
  // A message arrives in pieces of at most 64 KiB; `in_` holds the pieces of the current one until it is done. One
  // that grows past max_message is dropped piece by piece to its end (counted and logged once), never buffered.
  void read() {
    ws_.async_read_some(in_, 64 * 1024,
                        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }
  void on_read(beast::error_code ec) {
    if (ec) return gone();  // closed, reset or a protocol error: Beast has failed the connection
    if (in_.size() > server_.opt.max_message) {
      if (!dropping_) {
        server_.bad_messages.fetch_add(1);
        spdlog::warn("serve: a client sent a message over {} bytes; it was ignored", server_.opt.max_message);
      }
      dropping_ = true;
      in_.consume(in_.size());
    }
    if (!ws_.is_message_done()) return read();
    if (dropping_) {
      dropping_ = false;
    } else if (!ws_.got_text()) {
      server_.bad_messages.fetch_add(1);
      spdlog::warn("serve: ignored a binary message from a client ({} bytes)", in_.size());
    } else if (server_.cb.on_text) {
      const std::string text = beast::buffers_to_string(in_.data());
      if (!server_.cb.on_text(text)) server_.bad_messages.fetch_add(1);
    }
    in_.consume(in_.size());
    read();
  }
  void write_next() {
    if (writing_ || !open_) return;
    if (!texts_.empty()) {
      out_text_ = std::move(texts_.front());
      texts_.pop_front();
      ws_.text(true);
      writing_ = true;
      ws_.async_write(net::buffer(*out_text_),
                      [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_write(ec, false); });
    } else if (pending_ || surface_) {
      // Alternate when both wait: a stream of frames must not starve the surface, nor a surface the frames.
      const bool take_surface = surface_ && (!pending_ || !last_was_surface_);
      auto& slot = take_surface ? surface_ : pending_;
      last_was_surface_ = take_surface;
      out_frame_ = std::move(slot);
      slot.reset();
      ws_.binary(true);
      writing_ = true;
      ws_.async_write(net::buffer(*out_frame_),
                      [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_write(ec, true); });
    }
  }
  void on_write(beast::error_code ec, bool frame) {
    writing_ = false;
    out_text_.reset(), out_frame_.reset();
    if (ec) return gone();
    if (frame && !last_was_surface_) server_.frames_sent.fetch_add(1, std::memory_order_relaxed);
    write_next();
  }
  void gone() {
    open_ = false;
    pending_.reset();
    surface_.reset();
    texts_.clear();
    std::erase_if(server_.sessions, [this](const auto& w) {
      const auto s = w.lock();
      return !s || s.get() == this;
    });
    server_.clients = static_cast<int>(server_.sessions.size());
  }

  websocket::stream<beast::tcp_stream> ws_;
  WsServer::Impl& server_;
  beast::flat_buffer in_;
  bool open_ = false, writing_ = false, dropping_ = false, last_was_surface_ = false;
  std::shared_ptr<const Bytes> pending_, surface_, out_frame_;
  std::shared_ptr<const std::string> out_text_;
  std::deque<std::shared_ptr<const std::string>> texts_;
};

// One HTTP connection: static files, or the upgrade to a WebSocket on /ws.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, WsServer::Impl& server) : stream_(std::move(socket)), server_(server) {}
  void run() { read(); }

 private:
  void read() {
    parser_.emplace();
    parser_->body_limit(16 * 1024);   // GETs only: a request body is never needed
    parser_->header_limit(16 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buf_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }
  void on_read(beast::error_code ec) {
    if (ec == http::error::end_of_stream) {
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    if (ec) return;  // timeout, reset, a malformed or oversized request: drop the connection
    auto req = parser_->release();
    if (websocket::is_upgrade(req)) {
      if (req.target() != "/ws") return send(error(req, http::status::not_found, "not found\n"));
      if (server_.live_sessions() >= server_.opt.max_clients) {
        spdlog::warn("serve: refused a client: {} are connected (--max-clients)", server_.opt.max_clients);
        return send(error(req, http::status::service_unavailable, "too many clients\n"));
      }
      stream_.expires_never();  // the WebSocket has its own timeouts
      std::make_shared<WsSession>(stream_.release_socket(), server_)->run(std::move(req));
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head)
      return send(error(req, http::status::method_not_allowed, "method not allowed\n"));
    const StaticResult r = server_.files.resolve(std::string_view(req.target().data(), req.target().size()));
    if (r.status != 200)
      return send(error(req, static_cast<http::status>(r.status),
                        r.status == 403 ? "forbidden\n" : r.status == 400 ? "bad request\n" : "not found\n"));
    std::ifstream in(r.file, std::ios::binary);
    std::string body((std::istreambuf_iterator<char>(in)), {});
    if (!in && !in.eof()) return send(error(req, http::status::internal_server_error, "cannot read\n"));
    auto res = std::make_shared<http::response<http::string_body>>(http::status::ok, req.version());
    res->set(http::field::content_type, std::string(r.mime));
    res->set(http::field::cache_control, "no-cache");
    res->set("X-Content-Type-Options", "nosniff");
    res->keep_alive(req.keep_alive());
    if (req.method() == http::verb::head) {
      res->content_length(body.size());
    } else {
      res->body() = std::move(body);
      res->prepare_payload();
    }
    send(std::move(res));
  }
  static std::shared_ptr<http::response<http::string_body>> error(const http::request<http::string_body>& req,
                                                                  http::status status, std::string text) {
    auto res = std::make_shared<http::response<http::string_body>>(status, req.version());
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    res->keep_alive(req.keep_alive());
    res->body() = std::move(text);
    res->prepare_payload();
    return res;
  }
  void send(std::shared_ptr<http::response<http::string_body>> res) {
    const bool keep = res->keep_alive();
    http::async_write(stream_, *res, [self = shared_from_this(), res, keep](beast::error_code ec, std::size_t) {
      if (ec) return;
      if (!keep) {
        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
        return;
      }
      self->read();
    });
  }

  beast::tcp_stream stream_;
  WsServer::Impl& server_;
  beast::flat_buffer buf_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

void WsServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
    if (!ec) std::make_shared<HttpSession>(std::move(socket), *this)->run();
    accept();
  });
}

WsServer::WsServer(ServerOptions options, const StaticFiles& files, Callbacks callbacks)
    : impl_(std::make_unique<Impl>(std::move(options), files, std::move(callbacks))) {}

WsServer::~WsServer() { stop(); }

Status WsServer::start() {
  FF_CHECK(impl_->opt.validate());
  auto& a = impl_->acceptor;
  boost::system::error_code ec;
  const tcp::endpoint ep(net::ip::make_address(impl_->opt.bind, ec), impl_->opt.port);
  if (!ec) a.open(ep.protocol(), ec);
  // SO_REUSEADDR: a restarted server can bind again while the old connections sit in TIME_WAIT.
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    a.close();
    return io_error(fmt::format("cannot listen on {}:{}: {}", impl_->opt.bind, impl_->opt.port, ec.message()));
  }
  impl_->port = a.local_endpoint().port();
  if (impl_->cb.on_signal) {
    impl_->signals.add(SIGINT);
    impl_->signals.add(SIGTERM);
    impl_->signals.async_wait([this](beast::error_code e, int) {
      if (!e) impl_->cb.on_signal();
    });
  }
  impl_->accept();
  impl_->thread = std::thread([this] { impl_->ioc.run(); });
  return {};
}

std::uint16_t WsServer::port() const { return impl_->port; }

void WsServer::Impl::hand_over(std::shared_ptr<const Bytes> Impl::*slot, std::shared_ptr<const Bytes> item,
                               bool count_skipped, void (WsSession::*queue)(std::shared_ptr<const Bytes>)) {
  bool post = false;
  {
    std::lock_guard lock(slot_mu);
    post = !(this->*slot);
    // Replaced before the I/O thread took it: every client skipped it.
    if (!post && count_skipped) frames_skipped.fetch_add(std::uint64_t(clients.load()), std::memory_order_relaxed);
    this->*slot = std::move(item);
  }
  if (!post) return;  // the handler already on its way takes this one
  net::post(ioc, [this, slot, queue] {
    std::shared_ptr<const Bytes> newest;
    {
      std::lock_guard lock(slot_mu);
      newest = std::exchange(this->*slot, nullptr);
    }
    for (auto& w : sessions)
      if (auto s = w.lock()) ((*s).*queue)(newest);
  });
}

void WsServer::publish_frame(std::shared_ptr<const std::vector<std::uint8_t>> frame) {
  impl_->hand_over(&Impl::next_frame, std::move(frame), true, &WsSession::queue_frame);
}

void WsServer::publish_surface(std::shared_ptr<const std::vector<std::uint8_t>> surface) {
  impl_->hand_over(&Impl::next_surface, std::move(surface), false, &WsSession::queue_surface);
}

void WsServer::broadcast_text(std::string text) {
  auto t = std::make_shared<const std::string>(std::move(text));
  net::post(impl_->ioc, [this, t] {
    for (auto& w : impl_->sessions)
      if (auto s = w.lock()) s->queue_text(t);
  });
}

void WsServer::stop() {
  if (impl_->stopped.exchange(true)) return;
  if (impl_->thread.joinable()) {
    net::post(impl_->ioc, [this] {
      boost::system::error_code ec;
      impl_->acceptor.close(ec);
      impl_->signals.cancel(ec);
      for (auto& w : impl_->sessions)
        if (auto s = w.lock()) s->close();
    });
    // Close frames get a moment to go out; then everything left is cancelled and destroyed with the context.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    impl_->ioc.stop();
    impl_->thread.join();
  } else {
    boost::system::error_code ec;
    impl_->acceptor.close(ec);
  }
}

ServerStats WsServer::stats() const {
  return {impl_->frames_sent.load(), impl_->frames_skipped.load(), impl_->bad_messages.load()};
}

int WsServer::clients() const { return impl_->clients.load(); }

}  // namespace ff::server
