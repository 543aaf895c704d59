// The live page's HTTP server (page_server.hpp).
#include "web/page_server.hpp"

#include <atomic>
#include <chrono>
#include <thread>

#include <httplib.h>

#include "web/assets.hpp"

namespace dicesim::web {

struct PageServer::Impl {
  const LiveBoard* board;
  httplib::Server http;
  int port = 0;
  std::atomic<bool> stopping{false};
};

PageServer::PageServer(const LiveBoard& board) : impl_(std::make_unique<Impl>()) {
  impl_->board = &board;
  Impl* s = impl_.get();
  // One thread per open event stream: room for dozens of browsers (httplib's default is ~8).
  s->http.new_task_queue = [] { return new httplib::ThreadPool(64); };  // httplib owns and deletes it
  s->http.Get("/", [](const httplib::Request&, httplib::Response& res) {
    std::string page(kServeHtml);
    const auto at = [&](std::string_view key) { return page.find(key); };
    page.replace(at("@CSS@"), 5, kServeCss);
    page.replace(at("@SERVE@"), 7, kServeJs);
    res.set_content(page, "text/html; charset=utf-8");
  });
  s->http.Get("/state", [s](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(s->board->json(), "application/json");
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

bool PageServer::bind(const std::string& addr, int port) {
  if (port == 0) {
    impl_->port = impl_->http.bind_to_any_port(addr);
    return impl_->port > 0;
  }
  if (!impl_->http.bind_to_port(addr, port)) return false;
  impl_->port = port;
  return true;
}

int PageServer::port() const { return impl_->port; }

void PageServer::run() { impl_->http.listen_after_bind(); }

void PageServer::stop() {
  impl_->stopping = true;
  impl_->http.stop();
}

}  // namespace dicesim::web
