// The wire contract: encodings round-trip, hostile bytes are rejected before lcm-gen's decoders
// could over-allocate, and run_start rebuilds exactly the model `dicesim toss` compiles.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"

namespace w = dicesim::wire;

namespace {

dicesim_lcm::toss_batch sample_batch(int n) {
  dicesim_lcm::toss_batch b{};
  b.run_id = 5, b.worker_id = 6, b.lease_id = 7, b.first_index = 100, b.count = n;
  for (int i = 0; i < n; ++i) {
    b.faces.push_back(static_cast<std::int8_t>(1 + i % 6));
    b.statuses.push_back(0);
    b.bounces.push_back(i);
  }
  return b;
}

}  // namespace

TEST(LcmWire, TossBatchRoundTripsAndStaysOneDatagram) {
  const auto b = sample_batch(w::kMaxBatch);
  const auto bytes = w::encode(b);
  EXPECT_LT(bytes.size(), 64u * 1024u) << "a full batch must fit one UDP datagram";
  const auto d = w::decode<dicesim_lcm::toss_batch>(bytes.data(), bytes.size());
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->first_index, 100);
  EXPECT_EQ(d->faces, b.faces);
  EXPECT_EQ(d->bounces, b.bounces);
  EXPECT_EQ(d->n_corrected, 0);
}

// The corrections of the few tosses that had any (issue 13) travel with their offsets.
TEST(LcmWire, TossBatchCarriesCorrections) {
  auto b = sample_batch(10);
  b.n_corrected = 2;
  b.corrected_offset = {3, 7};
  b.energy_clamps = {0, 0};
  b.pgs_unconverged = {2, 1};
  b.overlap_fixes = {0, 0};
  b.fallbacks = {1, 0};
  const auto bytes = w::encode(b);
  const auto d = w::decode<dicesim_lcm::toss_batch>(bytes.data(), bytes.size());
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->corrected_offset, b.corrected_offset);
  EXPECT_EQ(d->pgs_unconverged, b.pgs_unconverged);
  EXPECT_EQ(d->fallbacks, b.fallbacks);
}

TEST(LcmWire, EveryTruncationOfEveryTypeIsRejected) {
  dicesim_lcm::worker_status s{};
  s.host = "h";
  s.held_leases = {1, 2};
  s.n_held = 2;
  dicesim_lcm::run_start r{};
  r.scene_text = "x = 1";
  r.overrides = {"a=1"};
  r.n_overrides = 1;
  const std::vector<std::vector<std::uint8_t>> all = {w::encode(sample_batch(3)), w::encode(s), w::encode(r)};
  for (std::size_t t = 0; t < all.size(); ++t)
    for (std::size_t cut = 0; cut < all[t].size(); ++cut) {
      const std::uint8_t* p = all[t].data();
      const bool ok = t == 0   ? w::decode<dicesim_lcm::toss_batch>(p, cut).has_value()
                      : t == 1 ? w::decode<dicesim_lcm::worker_status>(p, cut).has_value()
                               : w::decode<dicesim_lcm::run_start>(p, cut).has_value();
      EXPECT_FALSE(ok) << "type " << t << " cut at " << cut;
    }
  EXPECT_TRUE(w::decode<dicesim_lcm::run_start>(all[2].data(), all[2].size()).has_value());
  EXPECT_TRUE(w::decode<dicesim_lcm::worker_status>(all[1].data(), all[1].size()).has_value());
}

TEST(LcmWire, HugeCountsAndZeroLengthStringsAreRejected) {
  auto bytes = w::encode(sample_batch(4));
  bytes[48] = 0x7f;  // count = 2^31 - ... in a 76-byte payload
  EXPECT_FALSE(w::decode<dicesim_lcm::toss_batch>(bytes.data(), bytes.size()));
  bytes[48] = 0xff;  // negative
  EXPECT_FALSE(w::decode<dicesim_lcm::toss_batch>(bytes.data(), bytes.size()));
  dicesim_lcm::worker_status s{};
  auto sb = w::encode(s);
  // host's length field (after hash, utime, worker_id, run_id, pid) set to 0: lcm-gen would throw.
  sb[36] = sb[37] = sb[38] = sb[39] = 0;
  EXPECT_FALSE(w::decode<dicesim_lcm::worker_status>(sb.data(), sb.size()));
}

TEST(LcmWire, RandomBytesNeverCrash) {
  std::mt19937 rng(1);
  const auto base = w::encode(sample_batch(5));
  for (int i = 0; i < 20000; ++i) {
    auto b = base;
    for (int k = 0; k < 3; ++k) b[rng() % b.size()] = static_cast<std::uint8_t>(rng());
    b.resize(rng() % (b.size() + 8));
    (void)w::decode<dicesim_lcm::toss_batch>(b.data(), b.size());
    (void)w::decode<dicesim_lcm::run_start>(b.data(), b.size());
    (void)w::decode<dicesim_lcm::worker_status>(b.data(), b.size());
    (void)w::decode<dicesim_lcm::probabilities>(b.data(), b.size());
  }
}

TEST(LcmWire, RunStartRebuildsTheSameModelIncludingExtends) {
  for (const char* rel : {"/scenes/paper/die1.toml", "/scenes/paper/variants/die1-seed-swapped-restitution.toml"}) {
    const std::string path = std::string(DICESIM_SOURCE_DIR) + rel;
    const std::vector<std::string> overrides = {"throw.height.mean=0.7", "sim.fidelity=\"paper\""};
    const dicesim::DieModel direct = dicesim::compile(dicesim::load_scene(path, overrides), path);
    w::RunSpec spec;
    spec.run_id = 1;
    spec.origin = path;
    spec.files = w::read_scene_files(path);
    spec.overrides = overrides;
    spec.total = 10;
    spec.fingerprint = w::model_fingerprint(direct);
    // Through the wire and back, as a worker sees it.
    const auto bytes = w::encode(w::to_message(spec));
    const auto msg = w::decode<dicesim_lcm::run_start>(bytes.data(), bytes.size());
    ASSERT_TRUE(msg.has_value());
    const w::RunSpec back = w::from_message(*msg);
    EXPECT_EQ(back.files.size(), spec.files.size());
    EXPECT_EQ(w::model_fingerprint(w::compile_spec(back)), spec.fingerprint) << rel;
  }
  // And the fingerprint does see a change.
  const std::string die1 = std::string(DICESIM_SOURCE_DIR) + "/scenes/paper/die1.toml";
  EXPECT_NE(w::model_fingerprint(dicesim::compile(dicesim::load_scene(die1))),
            w::model_fingerprint(dicesim::compile(dicesim::load_scene(die1, {"throw.height.mean=0.7"}))));
}

TEST(LcmWire, RunStartWithEscapingPathsIsRefused) {
  w::RunSpec spec;
  spec.origin = "x.toml";
  spec.files = {{"../../etc/x.toml", "name = 'x'"}};
  EXPECT_THROW(w::compile_spec(spec), dicesim::SceneError);
  spec.files = {{"/etc/x.toml", "name = 'x'"}};
  EXPECT_THROW(w::compile_spec(spec), dicesim::SceneError);
}

TEST(LcmWire, UrlPrecedence) {
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(w::resolve_url(""), "udpm://239.255.76.67:7667?ttl=0");
  ::setenv("LCM_DEFAULT_URL", "udpm://239.255.76.67:7000?ttl=0", 1);
  EXPECT_EQ(w::resolve_url(""), "udpm://239.255.76.67:7000?ttl=0");
  EXPECT_EQ(w::resolve_url("udpm://239.255.76.67:7001?ttl=1"), "udpm://239.255.76.67:7001?ttl=1");
  ::unsetenv("LCM_DEFAULT_URL");
}
