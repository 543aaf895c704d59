// The live page's HTTP server (page_server.hpp).
#include "web/page_server.hpp"

#include <atomic>
#include <chrono>
#include <deque>
#include <mutex>
#include <thread>

#include <algorithm>
#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "web/assets.hpp"

namespace dicesim::web {

struct PageServer::Impl {
  const LiveBoard* board;
  httplib::Server http;
  int port = 0;
  std::atomic<bool> stopping{false};
  std::mutex trace_mu;
  TracePages trace_pages;
  // The last pages made: every browser on the page asks for the same few tosses.
  std::deque<std::pair<std::pair<std::int64_t, std::uint64_t>, TracePage>> trace_cache;
};

PageServer::PageServer(const LiveBoard& board) : impl_(std::make_unique<Impl>()) {
  impl_->board = &board;
  Impl* s = impl_.get();
  // One thread per open event stream: room for dozens of browsers (httplib's default is ~8).
  s->http.new_task_queue = [] { return new httplib::ThreadPool(64); };  // httplib owns and deletes it
  s->http.Get("/", [](const httplib::Request&, httplib::Response& res) {
    std::string page(kServeHtml);
    const auto at = [&](std::string_view key) { return page.find(key); };
    page.replace(at("@TITLE@"), 7, "dicesim serve");
    page.replace(at("@CSS@"), 5, kServeCss);
    page.replace(at("@SERVE@"), 7, kServeJs);
    res.set_content(page, "text/html; charset=utf-8");
  });
  s->http.Get("/state", [s](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(s->board->json(), "application/json");
  });
  s->http.Get("/trace", [s](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    std::int64_t run = 0;
    std::uint64_t index = 0;
    try {
      run = std::stoll(req.get_param_value("run"));
      index = std::stoull(req.get_param_value("index"));
    } catch (const std::exception&) {
      res.status = 400;
      res.set_content("trace?run=RUN_ID&index=I", "text/plain");
      return;
    }
    std::lock_guard lock(s->trace_mu);
    if (!s->trace_pages) {
      res.status = 404;
      res.set_content("no sampled tosses: dicesim serve was started without --trace-every", "text/plain");
      return;
    }
    const std::pair<std::int64_t, std::uint64_t> key{run, index};
    auto hit = std::find_if(s->trace_cache.begin(), s->trace_cache.end(), [&](const auto& e) { return e.first == key; });
    if (hit == s->trace_cache.end()) {
      s->trace_cache.emplace_back(key, s->trace_pages(run, index));
      if (s->trace_cache.size() > 4) s->trace_cache.pop_front();
      hit = std::prev(s->trace_cache.end());
    }
    res.status = hit->second.status;
    res.set_content(hit->second.html, "text/html; charset=utf-8");
  });
  s->http.Get("/events", [s](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    auto seen = std::make_shared<std::uint64_t>(~std::uint64_t{0});
    auto last = std::make_shared<std::chrono::steady_clock::time_point>();
    res.set_chunked_content_provider("text/event-stream", [s, seen, last](std::size_t, httplib::DataSink& sink) {
      using namespace std::chrono;
      if (s->stopping) return false;
      // At most 4 updates a second: the aggregator answers 4 times a second, heartbeats come more often.
      const auto next = *last + milliseconds(250);
      if (steady_clock::now() < next) std::this_thread::sleep_until(next);
      const std::uint64_t v = s->board->wait(*seen, milliseconds(2000));
      if (s->stopping) return false;
      std::string msg;
      if (v == *seen) {
        msg = ": keep-alive\n\n";
      } else {
        std::uint64_t version = 0;
        msg = "data: " + s->board->json(&version) + "\n\n";
        *seen = version;
        *last = steady_clock::now();
      }
      return sink.write(msg.data(), msg.size());
    });
  });
}

PageServer::~PageServer() { stop(); }

namespace {

// cpp-httplib binds with SO_REUSEPORT, so a second server on a port in use would bind as well and
// share it. A plain socket cannot: bound and closed first, it tells whether the port is free.
bool port_free(const std::string& addr, int port) {
  sockaddr_in v4{};
  sockaddr_in6 v6{};
  const bool is4 = inet_pton(AF_INET, addr.c_str(), &v4.sin_addr) == 1;
  if (!is4 && inet_pton(AF_INET6, addr.c_str(), &v6.sin6_addr) != 1) return true;  // a name: httplib resolves it
  const int fd = ::socket(is4 ? AF_INET : AF_INET6, SOCK_STREAM, 0);
  if (fd < 0) return true;
  const int one = 1;  // a port left in TIME_WAIT by an earlier server is free (only a listener is not)
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  int ok;
  if (is4) {
    v4.sin_family = AF_INET;
    v4.sin_port = htons(static_cast<std::uint16_t>(port));
    ok = ::bind(fd, reinterpret_cast<const sockaddr*>(&v4), sizeof v4);
  } else {
    v6.sin6_family = AF_INET6;
    v6.sin6_port = htons(static_cast<std::uint16_t>(port));
    ok = ::bind(fd, reinterpret_cast<const sockaddr*>(&v6), sizeof v6);
  }
  ::close(fd);
  return ok == 0;
}

}  // namespace

bool PageServer::bind(const std::string& addr, int port) {
  if (port != 0 && !port_free(addr, port)) return false;
  if (port == 0) {
    impl_->port = impl_->http.bind_to_any_port(addr);
    return impl_->port > 0;
  }
  if (!impl_->http.bind_to_port(addr, port)) return false;
  impl_->port = port;
  return true;
}

int PageServer::port() const { return impl_->port; }

void PageServer::set_trace_pages(TracePages pages) {
  std::lock_guard lock(impl_->trace_mu);
  impl_->trace_pages = std::move(pages);
  impl_->trace_cache.clear();
}

void PageServer::run() { impl_->http.listen_after_bind(); }

void PageServer::stop() {
  impl_->stopping = true;
  impl_->http.stop();
}

}  // namespace dicesim::web
