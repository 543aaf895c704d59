// lcm::LCM::handleTimeout that survives a lost tcpq:// hub. LCM 1.3.1's handleTimeout select()s on
// the provider's socket; the tcpq provider reports -1 once its hub connection is gone, and
// FD_SET(-1) aborts the process (glibc's fortify check: "bit out of range 0 - FD_SETSIZE"). With
// the connection down this waits instead and reports no message; the process's next publish
// reconnects, and the provider then subscribes every channel again (lcm_tcpq.c). A udpm:// bus
// always has its socket, so nothing changes there.
#pragma once

#include <chrono>
#include <thread>

#include <lcm/lcm-cpp.hpp>

namespace dicesim::wire {

inline int handle_timeout(lcm::LCM& bus, int ms) {
  if (bus.getFileno() < 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(ms > 0 ? ms : 1));
    return 0;
  }
  return bus.handleTimeout(ms);
}

// The same for a process that only listens (watch, record, bridge, serve): it never publishes, so
// nothing would reconnect it after a lost hub. While the connection is down it publishes an empty
// message on kReconnectChannel, which no dicesim process listens to (outside DICESIM_*: loggers do
// not record it): that publish reconnects, and the provider subscribes every channel again.
inline constexpr const char* kReconnectChannel = "dicesim_reconnect";
inline int listen_timeout(lcm::LCM& bus, int ms) {
  if (bus.getFileno() < 0) bus.publish(kReconnectChannel, "", 0);  // reconnects if the hub is back
  return handle_timeout(bus, ms);
}

}  // namespace dicesim::wire
