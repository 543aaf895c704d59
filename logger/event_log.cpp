#include "logger/event_log.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace dicesim::eventlog {
namespace {

// An event on disk: sync word, event number, timestamp, channel length, data length (all
// big-endian), then the channel and the data.
constexpr std::uint32_t kSync = 0xEDA1DA01;
constexpr std::uint64_t kHeader = 4 + 8 + 8 + 4 + 4;

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

// Why the bytes at `at` are not an event: said as precisely as the header allows.
std::string diagnose(const std::string& path, std::uint64_t at, std::uint64_t size, std::uint64_t events) {
  const std::string where = "'" + path + "': event " + std::to_string(events + 1) + " at byte " + std::to_string(at);
  unsigned char h[kHeader] = {};
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(at));
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const auto got = static_cast<std::uint64_t>(in.gcount());
  if (got >= 4 && be32(h) != kSync)
    return where + " does not start with the LCM event-log sync word: corrupt, or not an LCM log";
  if (got < kHeader)
    return where + " is truncated: " + std::to_string(size - at) + " bytes left of a " + std::to_string(kHeader) +
           "-byte header";
  const std::int32_t chan = static_cast<std::int32_t>(be32(h + 20)), len = static_cast<std::int32_t>(be32(h + 24));
  if (chan <= 0 || chan >= 1000 || len < 0)
    return where + " is corrupt: channel length " + std::to_string(chan) + ", data length " + std::to_string(len);
  const std::uint64_t need = kHeader + static_cast<std::uint64_t>(chan) + static_cast<std::uint64_t>(len);
  if (at + need > size)
    return where + " is truncated: it needs " + std::to_string(need) + " bytes, the file has " +
           std::to_string(size - at) + " left";
  return where + " is corrupt: it is not followed by another event or the end of the file";
}

}  // namespace

EventLogReader::EventLogReader(const std::string& path) : path_(path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw LogError("cannot read '" + path + "': " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw LogError("'" + path + "' is not a regular file");
  size_ = static_cast<std::uint64_t>(st.st_size);
  file_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!file_->good()) throw LogError("cannot open '" + path + "' as an LCM event log");
}

const lcm::LogEvent* EventLogReader::next() {
  const std::uint64_t at = offset_;
  const lcm::LogEvent* e = file_->readNextEvent();
  if (!e) {
    if (at == size_) return nullptr;
    throw LogError(diagnose(path_, at, size_, events_));
  }
  const std::uint64_t end = at + kHeader + e->channel.size() + static_cast<std::uint64_t>(e->datalen);
  // liblcm looks for the next sync word byte by byte: any bytes it skipped were not an event.
  const auto pos = ftello(file_->getFilePtr());
  if (pos < 0 || static_cast<std::uint64_t>(pos) != end)
    throw LogError("'" + path_ + "': " + std::to_string(static_cast<std::uint64_t>(pos) - end) + " bytes after event " +
                   std::to_string(events_ + 1) + " (at byte " + std::to_string(at) +
                   ") are not an event: truncated or corrupt");
  offset_ = end;
  ++events_;
  return e;
}

EventLogWriter::EventLogWriter(const std::string& path) {
  file_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!file_->good()) throw LogError("cannot write '" + path + "': " + std::strerror(errno));
}

bool EventLogWriter::write(std::int64_t utime, const std::string& channel, const void* data, std::size_t len) {
  lcm::LogEvent e;
  e.eventnum = 0;  // liblcm numbers the events
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<std::int32_t>(len);
  e.data = const_cast<void*>(data);  // LogEvent's field is non-const; writing only reads it
  if (file_->writeEvent(&e) != 0) return false;
  ++events_;
  bytes_ += kHeader + channel.size() + len;
  return true;
}

bool EventLogWriter::flush() { return std::fflush(file_->getFilePtr()) == 0; }

}  // namespace dicesim::eventlog
