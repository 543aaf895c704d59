#include "aggregator/checkpoint.hpp"

#include <array>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "aggregator/counts_json.hpp"
#include "messages/wire.hpp"

namespace dicesim::agg {
namespace {

using nlohmann::json;
constexpr const char* kFormat = "dicesim-checkpoint-1";

std::string to_hex(const std::vector<std::uint8_t>& b) {
  static const char* d = "0123456789abcdef";
  std::string s(b.size() * 2, '0');
  for (std::size_t i = 0; i < b.size(); ++i) s[2 * i] = d[b[i] >> 4], s[2 * i + 1] = d[b[i] & 15];
  return s;
}

std::vector<std::uint8_t> from_hex(const std::string& s) {
  if (s.size() % 2) throw std::runtime_error("odd-length hex");
  std::vector<std::uint8_t> b(s.size() / 2);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(std::stoi(s.substr(2 * i, 2), nullptr, 16));
  return b;
}

// The five count fields are counts_json.hpp's (shared with shard files); the corrections here are
// an array in for_each order.
json counts_json(const RunCounts& c) {
  json a = json::array();
  c.corrections.for_each([&](const char*, std::uint64_t n) { a.push_back(n); });
  return agg::count_fields_json(c, std::move(a));
}

RunCounts counts_from(const json& j) {
  RunCounts c = agg::count_fields_from(j);
  // The kinds in for_each order; a checkpoint written before the sustained phase's guards were
  // counted holds the first four (the rest start at 0).
  const auto k = j.at("corrections").get<std::vector<std::uint64_t>>();
  if (k.size() != 4 && k.size() != RunCorrections::kKinds)
    throw std::runtime_error("checkpoint: corrections has " + std::to_string(k.size()) + " counts, expected 4 or " +
                             std::to_string(RunCorrections::kKinds));
  std::size_t i = 0;
  c.corrections.for_each([&](const char*, std::uint64_t& n) { n = i < k.size() ? k[i] : 0; ++i; });
  return c;
}

}  // namespace

std::string to_json(const Checkpoint& c) {
  json leases = json::array();
  for (const auto& l : c.leases) leases.push_back({l.id, l.worker, l.first, l.count});
  json blocks = json::array();
  for (const auto& [b, counts] : c.blocks) blocks.push_back({{"block", b}, {"counts", counts_json(counts)}});
  json received = json::array();
  for (const auto& r : c.received) received.push_back({r.first, r.second});
  const HealthCounts& h = c.health;
  const json j = {
      {"format", kFormat},
      {"run_id", std::to_string(c.start.run_id)},  // for people reading it; run_start is the truth
      {"written_utime", c.written_utime},
      {"elapsed_s", c.elapsed_s},
      {"finished", c.finished},
      {"resumes", c.resumes},
      {"run_start", to_hex(wire::encode(c.start))},
      {"labels", c.labels},
      {"target_halfwidth", c.target_halfwidth},
      {"limit", c.limit},
      {"received", received},
      {"frontier", c.frontier},
      {"next_lease", c.next_lease},
      {"prefix_end", c.prefix_end},
      {"prefix", counts_json(c.prefix)},
      {"all", counts_json(c.all)},
      {"blocks", blocks},
      {"leases", leases},
      {"health",
       {{"batches", h.batches}, {"duplicates", h.duplicates}, {"foreign", h.foreign}, {"malformed", h.malformed},
        {"range", h.range}, {"released", h.released}, {"leases", h.leases}, {"messages_out", h.messages_out},
        {"messages_in", h.messages_in}, {"unauthenticated", h.unauthenticated}}}};
  return j.dump() + "\n";
}

Checkpoint checkpoint_from_json(const std::string& text, const std::string& path) {
  Checkpoint c;
  try {
    const json j = json::parse(text);
    if (!j.is_object() || j.value("format", "") != kFormat)
      throw CheckpointError("'" + path + "' is not a dicesim checkpoint (no \"format\": \"" + kFormat + "\")");
    const auto bytes = from_hex(j.at("run_start").get<std::string>());
    auto start = wire::decode<dicesim_lcm::run_start>(bytes.data(), bytes.size());
    if (!start && wire::legacy_format(bytes.data(), bytes.size()))
      throw CheckpointError("'" + path + "' was written before runs carried any number of outcomes (its run_start is a " +
                            wire::legacy_format(bytes.data(), bytes.size()) + "): it cannot be resumed by this dicesim");
    if (!start || start->run_id == 0 || start->total_tosses <= 0)
      throw CheckpointError("'" + path + "': its run_start does not decode (a checkpoint of another dicesim version?)");
    c.start = *start;
    c.written_utime = j.at("written_utime").get<std::int64_t>();
    c.elapsed_s = j.at("elapsed_s").get<double>();
    c.finished = j.at("finished").get<bool>();
    c.resumes = j.at("resumes").get<int>();
    c.labels = j.at("labels").get<std::vector<int>>();
    c.target_halfwidth = j.at("target_halfwidth").get<double>();
    c.limit = j.at("limit").get<std::uint64_t>();
    for (const auto& r : j.at("received")) c.received.emplace_back(r.at(0).get<std::uint64_t>(), r.at(1).get<std::uint64_t>());
    c.frontier = j.at("frontier").get<std::uint64_t>();
    c.next_lease = j.at("next_lease").get<std::int64_t>();
    c.prefix_end = j.at("prefix_end").get<std::uint64_t>();
    c.prefix = counts_from(j.at("prefix"));
    c.all = counts_from(j.at("all"));
    for (const auto& b : j.at("blocks")) c.blocks[b.at("block").get<std::uint64_t>()] = counts_from(b.at("counts"));
    for (const auto& l : j.at("leases"))
      c.leases.push_back({l.at(0).get<std::int64_t>(), l.at(1).get<std::int64_t>(), l.at(2).get<std::uint64_t>(),
                          l.at(3).get<std::uint64_t>()});
    const json& h = j.at("health");
    HealthCounts& o = c.health;
    o.batches = h.at("batches"), o.duplicates = h.at("duplicates"), o.foreign = h.at("foreign");
    o.malformed = h.at("malformed"), o.range = h.at("range"), o.released = h.at("released"), o.leases = h.at("leases");
    o.messages_out = h.at("messages_out"), o.messages_in = h.at("messages_in"), o.unauthenticated = h.at("unauthenticated");
  } catch (const CheckpointError&) {
    throw;
  } catch (const std::exception& e) {
    throw CheckpointError("'" + path + "' is not a readable dicesim checkpoint: " + e.what());
  }
  // Consistency: what the rest of the code relies on.
  const std::uint64_t total = static_cast<std::uint64_t>(c.start.total_tosses);
  std::uint64_t prev = 0, held = 0;
  for (const auto& [lo, hi] : c.received) {
    if (lo < prev || hi <= lo || hi > total)
      throw CheckpointError("'" + path + "': the set of indices held is not a sorted list of ranges inside [0, " +
                            std::to_string(total) + ")");
    prev = hi, held += hi - lo;
  }
  if (c.limit > total || c.frontier > total || c.prefix_end > c.limit || c.all.total() != held || c.next_lease < 1)
    throw CheckpointError("'" + path + "' is inconsistent (limit, frontier, prefix or counts do not match the indices held)");
  // Every count has one entry per outcome of the run_start's die.
  bool sizes = std::vector<int>(c.start.outcome_labels.begin(), c.start.outcome_labels.end()) == c.labels &&
               c.prefix.faces.size() == c.labels.size() && c.all.faces.size() == c.labels.size();
  for (const auto& [b, counts] : c.blocks) sizes = sizes && counts.faces.size() == c.labels.size();
  if (!sizes)
    throw CheckpointError("'" + path + "' is inconsistent (its labels or per-outcome counts do not match its run_start's " +
                          std::to_string(c.start.outcome_labels.size()) + " outcomes)");
  return c;
}

Checkpoint read_checkpoint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CheckpointError("cannot read checkpoint '" + path + "': " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return checkpoint_from_json(s.str(), path);
}

void write_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  auto fail = [&](const std::string& what) {
    const std::string why = std::strerror(errno);
    throw std::runtime_error("checkpoint '" + path + "': " + what + ": " + why);
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) fail("cannot create " + tmp);
  std::size_t off = 0;
  while (off < text.size()) {
    const ssize_t n = ::write(fd, text.data() + off, text.size() - off);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      fail("write");
    }
    off += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    fail("fsync");
  }
  if (::close(fd) != 0) fail("close");
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail("rename");
  // The rename itself is only durable once the directory is.
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) fail("open directory " + dir);
  const int r = ::fsync(dfd);
  ::close(dfd);
  if (r != 0) fail("fsync directory " + dir);
}

CheckpointWriter::CheckpointWriter(std::string path) : path_(std::move(path)), thread_([this] { loop(); }) {}

CheckpointWriter::~CheckpointWriter() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void CheckpointWriter::submit(std::string text) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    pending_ = std::move(text);
  }
  cv_.notify_all();
}

void CheckpointWriter::flush() {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait(lock, [this] { return !pending_ && !busy_; });
}

CheckpointWriter::Stats CheckpointWriter::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

void CheckpointWriter::loop() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    cv_.wait(lock, [this] { return pending_ || stop_; });
    if (!pending_) return;  // stop, nothing left
    std::string text = std::move(*pending_);
    pending_.reset();
    busy_ = true;
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    std::string error;
    try {
      write_atomic(path_, text);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lock.lock();
    busy_ = false;
    if (error.empty()) {
      ++stats_.writes;
      stats_.bytes += text.size();
      stats_.write_s += s;
      stats_.max_write_s = std::max(stats_.max_write_s, s);
    } else {
      stats_.error = error;
    }
    cv_.notify_all();
  }
}

}  // namespace dicesim::agg
