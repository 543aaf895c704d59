// `dicesim serve`'s HTTP server (cpp-httplib): GET / is the live page (web/serve.html), GET /state
// the board's JSON, GET /events the same as server-sent events, sent when it changes (at most
// 4 times a second) and as a keep-alive comment every 2 s otherwise.
#pragma once

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
  int port() const;
  // Serves until stop() (from another thread or a signal's watcher).
  void run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dicesim::web
