#include "apps/lcm_hub.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

namespace dicesim {
namespace {

// A port the kernel has just found free on loopback (a small race with other programs remains).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return 0;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(fd);
  return port;
}

bool accepts(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  for (std::size_t at = 0; at <= dirs.size();) {
    const std::size_t end = std::min(dirs.find(':', at), dirs.size());
    if (::access((dirs.substr(at, end - at) + "/" + program).c_str(), X_OK) == 0) return true;
    at = end + 1;
  }
  return false;
}

}  // namespace

std::string lcm_jar_path() {
  const char* env = std::getenv("DICESIM_LCM_JAR");
  return env && *env ? env : "/usr/share/java/lcm.jar";
}

std::vector<std::string> hub_command(int port) {
  return {"java", "-cp", lcm_jar_path(), "lcm.lcm.TCPService", std::to_string(port)};
}

std::string hub_missing() {
  if (!std::filesystem::exists(lcm_jar_path()))
    return "no " + lcm_jar_path() + " (LCM's TCP hub; Debian package liblcm-java, or set DICESIM_LCM_JAR)";
  if (!on_path("java")) return "no java on PATH (the hub needs a Java runtime: Debian package default-jre-headless)";
  return "";
}

std::string HubProcess::start() {
  if (std::string why = hub_missing(); !why.empty()) return why;
  port_ = free_port();
  if (port_ == 0) return "no free TCP port on loopback";
  const std::vector<std::string> cmd = hub_command(port_);
  std::vector<char*> argv;
  for (const std::string& s : cmd) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  pid_ = ::fork();
  if (pid_ < 0) return "cannot fork the hub";
  if (pid_ == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);  // never outlives the run, even one killed outright
    if (::getppid() != parent) ::_exit(1);
    // TCPService prints a line per client: the run's stderr is for the run.
    if (FILE* devnull = std::fopen("/dev/null", "w")) ::dup2(::fileno(devnull), STDOUT_FILENO);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  // The JVM starts in about half a second on an idle machine; allow a loaded one 30 s.
  for (int i = 0; i < 600; ++i) {
    if (accepts(port_)) return "";
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return "the hub (java lcm.lcm.TCPService) exited at start";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  stop();
  return "the hub did not accept connections on port " + std::to_string(port_) + " within 30 s";
}

void HubProcess::stop() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  for (int i = 0; i < 40; ++i) {
    if (::waitpid(pid_, nullptr, WNOHANG) == pid_) {
      pid_ = -1;
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(pid_, SIGKILL);
  ::waitpid(pid_, nullptr, 0);
  pid_ = -1;
}

}  // namespace dicesim
