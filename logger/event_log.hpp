// LCM event-log files (the format of the stock lcm-logger / lcm-logplayer), read and written
// through liblcm's own lcm::LogFile. liblcm's reader skips bytes it cannot parse and stops at the
// first broken event without saying why; EventLogReader checks that every byte of the file belongs
// to an event, so a truncated or corrupt log is an error with its byte offset, never a short run.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include <lcm/lcm-cpp.hpp>

namespace dicesim::eventlog {

// The log cannot be read, is not an event log, is truncated or corrupt, or does not hold what was
// asked of it: bad input (exit 2).
struct LogError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class EventLogReader {
 public:
  explicit EventLogReader(const std::string& path);  // throws LogError
  // The next event (valid until the next call), or null at the clean end of the file. Throws
  // LogError when the bytes at the current offset are not one whole event.
  const lcm::LogEvent* next();
  std::uint64_t events() const { return events_; }
  std::uint64_t offset() const { return offset_; }  // bytes consumed
  std::uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::uint64_t size_ = 0, offset_ = 0, events_ = 0;
};

class EventLogWriter {
 public:
  explicit EventLogWriter(const std::string& path);  // truncates; throws LogError
  // false if the write failed (disk full, ...).
  bool write(std::int64_t utime, const std::string& channel, const void* data, std::size_t len);
  bool flush();
  std::uint64_t events() const { return events_; }
  std::uint64_t bytes() const { return bytes_; }

 private:
  std::unique_ptr<lcm::LogFile> file_;
  std::uint64_t events_ = 0, bytes_ = 0;
};

}  // namespace dicesim::eventlog
