// Test helper for the LCM integration scenarios (tests/integration/lcm_scenarios.sh).
//   lcm_inject hostile        waits for a run_start, then publishes foreign, out-of-range,
//                             out-of-domain, truncated and garbage messages on every channel
//   lcm_inject progress FRACTION SECONDS
//                             returns 0 as soon as a running run has done >= FRACTION of its
//                             tosses (from DICESIM_PROBABILITIES); 1 if it finished or time ran out
//   lcm_inject forge          a forger who knows the run id (from run_start, seal stripped) but not
//                             the key: publishes toss_batch messages claiming the last outcome for every index
//                             (from the top, so they come before the workers' results), unsealed,
//                             sealed with a wrong key, and genuine sealed batches with their outcomes
//                             changed; plus `finished` probabilities and a run_start with another
//                             seed, to stop or mislead the workers. Prints how many of each it sent.
//   lcm_inject count CHANNEL SECONDS
//                             prints how many valid messages of CHANNEL's type arrived
//                             (after SECONDS, or at SIGTERM)
// URL: $LCM_DEFAULT_URL (the scenario's private namespace).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "messages/auth.hpp"
#include "messages/wire.hpp"

namespace w = dicesim::wire;

namespace {

std::atomic<bool> g_stop{false};
void on_term(int) { g_stop = true; }

struct Listener {
  std::string want;
  int count = 0;
  dicesim_lcm::run_start run;
  bool have_run = false;
  double fraction = -1.0;  // progress mode
  int progress = -1;       // -1 waiting, 0 reached while running, 1 finished first
  std::int64_t done = 0;
  std::vector<std::uint8_t> captured;  // a genuine (sealed) toss_batch, for the forger to tamper with
  void handle(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    // A seal is not a secret: anyone can strip it and read the message (only forging needs the key).
    const std::size_t len = w::looks_sealed(rb->data, rb->data_size) ? rb->data_size - w::kSealSize : rb->data_size;
    if (ch == w::kRunStart) {
      if (auto m = w::decode<dicesim_lcm::run_start>(rb->data, len)) run = *m, have_run = true;
    }
    if (ch == w::kTossBatch && captured.empty() && len != rb->data_size) {
      // A worker's, not one of our own forgeries (worker id 42) coming back.
      if (auto b = w::decode<dicesim_lcm::toss_batch>(rb->data, len); b && b->worker_id != 42) {
        const auto* p = static_cast<const std::uint8_t*>(rb->data);
        captured.assign(p, p + rb->data_size);
      }
    }
    if (fraction >= 0 && ch == w::kProbabilities && progress < 0) {
      if (auto m = w::decode<dicesim_lcm::probabilities>(rb->data, len)) {
        done = m->done;
        if (m->finished) progress = 1;
        else if (m->total > 0 && static_cast<double>(m->done) >= fraction * static_cast<double>(m->total)) progress = 0;
      }
    }
    if (ch != want) return;
    bool ok = false;
    if (ch == w::kBounceState) ok = w::decode<dicesim_lcm::bounce_state>(rb->data, len).has_value();
    else if (ch == w::kProbabilities) ok = w::decode<dicesim_lcm::probabilities>(rb->data, len).has_value();
    else if (ch == w::kTossBatch) ok = w::decode<dicesim_lcm::toss_batch>(rb->data, len).has_value();
    else if (ch == w::kWorkerStatus) ok = w::decode<dicesim_lcm::worker_status>(rb->data, len).has_value();
    count += ok ? 1 : 0;
  }
};

template <class T>
void send(lcm::LCM& bus, const char* ch, const T& m, int* sent) {
  const auto b = w::encode(m);
  bus.publish(ch, b.data(), static_cast<unsigned>(b.size()));
  ++*sent;
  std::this_thread::sleep_for(std::chrono::milliseconds(2));  // pace: no flood, no drops
}

void send_raw(lcm::LCM& bus, const char* ch, const std::vector<std::uint8_t>& b, int* sent) {
  bus.publish(ch, b.data(), static_cast<unsigned>(b.size()));
  ++*sent;
  std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

dicesim_lcm::toss_batch batch(std::int64_t run, std::int64_t first, int n, int outcome, int status) {
  dicesim_lcm::toss_batch b{};
  b.run_id = run;
  b.worker_id = 42;
  b.lease_id = 1;
  b.first_index = first;
  b.count = n;
  b.outcomes.assign(static_cast<std::size_t>(n), static_cast<std::int8_t>(outcome));
  b.statuses.assign(static_cast<std::size_t>(n), static_cast<std::int8_t>(status));
  b.bounces.assign(static_cast<std::size_t>(n), 3);
  return b;
}

int hostile(lcm::LCM& bus, Listener& in) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!in.have_run) {
    bus.handleTimeout(100);
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(30)) return 1;
  }
  const std::int64_t run = in.run.run_id, total = in.run.total_tosses;
  int foreign = 0, range = 0, malformed = 0;
  // Another run's messages on every channel the aggregator reads.
  send(bus, w::kTossBatch, batch(run + 1, 0, 10, 1, 0), &foreign);
  dicesim_lcm::worker_status st{};
  st.run_id = run + 1;
  st.worker_id = 7;
  st.state = 1;
  send(bus, w::kWorkerStatus, st, &foreign);
  dicesim_lcm::run_start other = in.run;
  other.run_id = run + 1;
  other.total_tosses = 5;
  send(bus, w::kRunStart, other, &foreign);
  // Indices outside [0, total).
  send(bus, w::kTossBatch, batch(run, total, 10, 1, 0), &range);
  send(bus, w::kTossBatch, batch(run, total - 5, 10, 1, 0), &range);
  send(bus, w::kTossBatch, batch(run, -3, 10, 1, 0), &range);
  // Fields outside their domain: no outcome or one past the die's when settled, an outcome when
  // unresolved, status 3.
  const int outcomes = in.run.n_outcomes;
  send(bus, w::kTossBatch, batch(run, 0, 10, -1, 0), &malformed);
  send(bus, w::kTossBatch, batch(run, 0, 10, outcomes, 0), &malformed);
  send(bus, w::kTossBatch, batch(run, 0, 10, 2, 1), &malformed);
  send(bus, w::kTossBatch, batch(run, 0, 10, -1, 3), &malformed);
  // Claims of more outcomes than the wire carries (kMaxOutcomes): an answer and a run_start.
  dicesim_lcm::probabilities many{};
  many.run_id = run;
  many.n_outcomes = w::kMaxOutcomes + 1;
  for (int i = 0; i < many.n_outcomes; ++i) many.labels.push_back(i);
  many.counts.assign(many.labels.size(), 0);
  many.p = many.ci_lo = many.ci_hi = std::vector<double>(many.labels.size(), 0.0);
  send(bus, w::kProbabilities, many, &malformed);
  dicesim_lcm::run_start wide = in.run;
  wide.n_outcomes = many.n_outcomes;
  wide.outcome_labels = many.labels;
  send(bus, w::kRunStart, wide, &malformed);
  // Truncated encodings of a valid message, and garbage, on every channel.
  std::mt19937 rng(12345);
  const auto good = w::encode(batch(run, 0, 10, 1, 0));
  for (const char* ch : {w::kRunStart, w::kWorkLease, w::kTossBatch, w::kBounceState, w::kWorkerStatus, w::kProbabilities}) {
    for (std::size_t cut : {std::size_t{0}, std::size_t{4}, std::size_t{9}, good.size() / 2, good.size() - 1})
      send_raw(bus, ch, std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<long>(cut)), &malformed);
    for (int k = 0; k < 5; ++k) {
      std::vector<std::uint8_t> junk(static_cast<std::size_t>(rng() % 300));
      for (auto& c : junk) c = static_cast<std::uint8_t>(rng());
      if (k == 0 && junk.size() >= 8) {  // the right type hash, then junk: gets past the hash check
        const auto g = w::encode(batch(run, 0, 1, 1, 0));
        std::memcpy(junk.data(), g.data(), 8);
      }
      send_raw(bus, ch, junk, &malformed);
    }
  }
  // A count that claims 2^31-1 tosses in a 60-byte message.
  auto huge = w::encode(batch(run, 0, 1, 1, 0));
  huge[48] = 0x7f, huge[49] = 0xff, huge[50] = 0xff, huge[51] = 0xff;
  send_raw(bus, w::kTossBatch, huge, &malformed);
  std::printf("sent foreign %d, out of range %d, malformed %d\n", foreign, range, malformed);
  return 0;
}

int forge(lcm::LCM& bus, Listener& in) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!in.have_run) {
    bus.handleTimeout(20);
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(30)) return 1;
  }
  const std::int64_t run = in.run.run_id, total = in.run.total_tosses;
  std::vector<std::uint8_t> wrong_key(32);
  std::mt19937 rng(777);
  for (auto& b : wrong_key) b = static_cast<std::uint8_t>(rng());
  w::Sealer wrong(wrong_key);
  int unsealed = 0, wrong_sealed = 0, tampered = 0, to_workers = 0;
  // Every index claimed as the die's last outcome (a settled toss), top down: the workers start at index 0.
  for (std::int64_t first = total; first > 0;) {
    const int n = static_cast<int>(std::min<std::int64_t>(w::kMaxBatch, first));
    first -= n;
    auto bytes = w::encode(batch(run, first, n, in.run.n_outcomes - 1, 0));
    send_raw(bus, w::kTossBatch, bytes, &unsealed);
    wrong.seal(w::kTossBatch, bytes);
    send_raw(bus, w::kTossBatch, bytes, &wrong_sealed);
    if (in.captured.empty()) bus.handleTimeout(0);
  }
  // The scenario starts the workers only now: every index is claimed by a forgery first.
  std::printf("forged batches: unsealed %d, wrong key %d\n", unsealed, wrong_sealed);
  std::fflush(stdout);
  // A genuine batch, faces changed, seal kept: the MAC covers every byte.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (in.captured.empty() && std::chrono::steady_clock::now() < until) bus.handleTimeout(20);
  if (in.captured.empty()) {
    std::fprintf(stderr, "forge: no sealed toss_batch heard\n");
    return 1;
  }
  // The workers are at work: messages that would stop or mislead the workers: "finished", and the run with another seed.
  dicesim_lcm::probabilities fin{};
  fin.run_id = run;
  fin.finished = 1;
  fin.total = total;
  fin.n_outcomes = in.run.n_outcomes;
  fin.labels = in.run.outcome_labels;
  fin.counts.assign(fin.labels.size(), 0);
  fin.p = fin.ci_lo = fin.ci_hi = std::vector<double>(fin.labels.size(), 0.0);
  dicesim_lcm::run_start other = in.run;
  other.seed += 1;
  for (int k = 0; k < 5; ++k) {
    // Spread over ~0.6 s: on a loaded machine a worker process may start a few hundred ms after
    // the other, and each must hear (and drop) some of these.
    if (k > 0) std::this_thread::sleep_for(std::chrono::milliseconds(150));
    send(bus, w::kProbabilities, fin, &to_workers);
    auto bytes = w::encode(fin);
    wrong.seal(w::kProbabilities, bytes);
    send_raw(bus, w::kProbabilities, bytes, &to_workers);
    send(bus, w::kRunStart, other, &to_workers);
  }
  for (int k = 0; k < 20; ++k) {
    std::vector<std::uint8_t> t = in.captured;
    // Payload: hash 8, utime run worker lease first 5x8, count 4, then outcomes (count bytes):
    // another valid outcome index.
    const std::size_t o0 = 8 + 5 * 8 + 4 + static_cast<std::size_t>(k);
    t[o0] = static_cast<std::uint8_t>((static_cast<std::int8_t>(t[o0]) + 1 + in.run.n_outcomes) % in.run.n_outcomes);
    if (k % 2) t[t.size() - 1] ^= 1;  // and a flipped bit of the tag itself
    send_raw(bus, w::kTossBatch, t, &tampered);
  }
  std::printf("forged later: tampered %d, aimed at workers %d\n", tampered, to_workers);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  lcm::LCM bus(w::resolve_url(""));
  if (!bus.good()) return 2;
  Listener in;
  bus.subscribe(".*", &Listener::handle, &in)->setQueueCapacity(100000);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "hostile") return hostile(bus, in);
  if (mode == "forge") return forge(bus, in);
  if (mode == "progress" && argc == 4) {
    in.fraction = std::stod(argv[2]);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(std::stod(argv[3]));
    while (in.progress < 0 && std::chrono::steady_clock::now() < end) bus.handleTimeout(20);
    std::printf("progress: %lld tosses done%s\n", static_cast<long long>(in.done), in.progress == 0 ? "" : " (too late)");
    return in.progress == 0 ? 0 : 1;
  }
  if (mode == "count" && argc == 4) {
    in.want = argv[2];
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(std::stod(argv[3]));
    std::signal(SIGTERM, on_term);  // stop early, still print the count
    while (!g_stop && std::chrono::steady_clock::now() < end) bus.handleTimeout(50);
    std::printf("%d\n", in.count);
    return 0;
  }
  std::fprintf(stderr, "usage: lcm_inject hostile | forge | progress FRACTION SECONDS | count CHANNEL SECONDS\n");
  return 2;
}
