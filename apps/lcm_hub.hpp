// LCM's own TCP hub, `lcm.lcm.TCPService` from Debian's liblcm-java, run by a Java runtime: every
// message a client publishes is relayed to every client subscribed to its channel. Processes reach
// it with the C library's `tcpq://HOST:PORT` provider, so a run needs no multicast at all.
// `dicesim hub` runs it in the foreground; `dicesim run --transport tcp` starts one of its own.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace dicesim {

// The jar holding lcm.lcm.TCPService: $DICESIM_LCM_JAR, else Debian's /usr/share/java/lcm.jar.
std::string lcm_jar_path();
// argv of the hub on `port`: java -cp JAR lcm.lcm.TCPService PORT (TCPService binds every
// interface: the port is reachable from any host that can route to this one).
std::vector<std::string> hub_command(int port);
// Why the hub cannot start here (no jar, no java on PATH), or "" when it can.
std::string hub_missing();

// A hub child process on a free loopback-chosen port, stopped (SIGTERM, then SIGKILL) on
// destruction. start() returns once the port accepts connections.
class HubProcess {
 public:
  HubProcess() = default;
  HubProcess(const HubProcess&) = delete;
  HubProcess& operator=(const HubProcess&) = delete;
  ~HubProcess() { stop(); }
  // Starts the hub; "" on success, else why not.
  std::string start();
  void stop();
  int port() const { return port_; }
  std::string url() const { return "tcpq://127.0.0.1:" + std::to_string(port_); }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
};

}  // namespace dicesim
