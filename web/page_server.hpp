// `dicesim serve`'s HTTP server (cpp-httplib): GET / is the live page (web/serve.html), GET /state
// the board's JSON, GET /events the same as server-sent events, sent when it changes (at most
// 4 times a second) and as a keep-alive comment every 2 s otherwise. With trace pages (serve
// --trace-every), GET /trace?run=R&index=I is the `dicesim show` page of that toss of run R.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "web/live_board.hpp"

namespace dicesim::web {

class PageServer {
 public:
  explicit PageServer(const LiveBoard& board);
  ~PageServer();
  PageServer(const PageServer&) = delete;
  PageServer& operator=(const PageServer&) = delete;

  // Binds addr:port (port 0: any free port); false when that is impossible (in use, no such
  // address, no permission).
  bool bind(const std::string& addr, int port);
  // The page of toss `index` of run `run_id`: an HTTP status (200, or 404 with a page saying why)
  // and the HTML. Called from the HTTP threads, at most once at a time (callers wait).
  struct TracePage {
    int status = 404;
    std::string html;
  };
  using TracePages = std::function<TracePage(std::int64_t run_id, std::uint64_t index)>;
  void set_trace_pages(TracePages pages);
  int port() const;
  // Serves until stop() (from another thread or a signal's watcher).
  void run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dicesim::web
