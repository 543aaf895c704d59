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
    b.outcomes.push_back(static_cast<std::int8_t>(i % 6));
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
  EXPECT_EQ(d->outcomes, b.outcomes);
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
  // The sustained phase's guards (issue 39) travel the same way.
  b.located_capped = {0, 3};
  b.support_search_capped = {4, 0};
  b.rise_dropped = {0, 5};
  b.contact_overlaps = {6, 0};
  b.nudges = {0, 2};
  const auto bytes = w::encode(b);
  EXPECT_TRUE(w::plausible_toss_batch(bytes.data(), bytes.size()));
  const auto d = w::decode<dicesim_lcm::toss_batch>(bytes.data(), bytes.size());
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->corrected_offset, b.corrected_offset);
  EXPECT_EQ(d->pgs_unconverged, b.pgs_unconverged);
  EXPECT_EQ(d->fallbacks, b.fallbacks);
  EXPECT_EQ(d->located_capped, b.located_capped);
  EXPECT_EQ(d->support_search_capped, b.support_search_capped);
  EXPECT_EQ(d->rise_dropped, b.rise_dropped);
  EXPECT_EQ(d->contact_overlaps, b.contact_overlaps);
  EXPECT_EQ(d->nudges, b.nudges);
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
  r.n_outcomes = 2;
  r.outcome_labels = {3, 8};
  r.n_assets = 1;
  r.asset_paths = {"m.obj"};
  r.asset_texts = {"v 0 0 0"};
  dicesim_lcm::probabilities pr{};
  pr.n_outcomes = 2;
  pr.labels = {3, 8};
  pr.counts = {1, 2};
  pr.p = pr.ci_lo = pr.ci_hi = {0.5, 0.5};
  const std::vector<std::vector<std::uint8_t>> all = {w::encode(sample_batch(3)), w::encode(s), w::encode(r), w::encode(pr)};
  for (std::size_t t = 0; t < all.size(); ++t)
    for (std::size_t cut = 0; cut < all[t].size(); ++cut) {
      const std::uint8_t* p = all[t].data();
      const bool ok = t == 0   ? w::decode<dicesim_lcm::toss_batch>(p, cut).has_value()
                      : t == 1 ? w::decode<dicesim_lcm::worker_status>(p, cut).has_value()
                      : t == 2 ? w::decode<dicesim_lcm::run_start>(p, cut).has_value()
                               : w::decode<dicesim_lcm::probabilities>(p, cut).has_value();
      EXPECT_FALSE(ok) << "type " << t << " cut at " << cut;
    }
  EXPECT_TRUE(w::decode<dicesim_lcm::run_start>(all[2].data(), all[2].size()).has_value());
  EXPECT_TRUE(w::decode<dicesim_lcm::probabilities>(all[3].data(), all[3].size()).has_value());
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
    spec.labels = direct.outcome_labels;
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

// Any die travels: its outcome labels, and a mesh die's OBJ text (no side file on the worker).
TEST(LcmWire, RunStartCarriesOutcomeLabelsAndAMeshsObjText) {
  for (const char* rel : {"/scenes/dice/d20.toml", "/scenes/dice/d4.toml", "/scenes/dice/hollow-d6.toml"}) {
    const std::string path = std::string(DICESIM_SOURCE_DIR) + rel;
    const dicesim::DieModel direct = dicesim::compile(dicesim::load_scene(path), path);
    const w::RunSpec spec = w::make_run_spec(3, path, {}, direct, 1, 10);
    EXPECT_EQ(spec.labels, direct.outcome_labels) << rel;
    const bool mesh = std::string(rel).find("hollow") != std::string::npos;
    ASSERT_EQ(spec.assets.size(), mesh ? 1u : 0u) << rel;
    const auto bytes = w::encode(w::to_message(spec));
    const auto msg = w::decode<dicesim_lcm::run_start>(bytes.data(), bytes.size());
    ASSERT_TRUE(msg.has_value()) << rel;
    EXPECT_EQ(msg->n_outcomes, direct.outcomes());
    const w::RunSpec back = w::from_message(*msg);
    EXPECT_EQ(back.labels, direct.outcome_labels);
    if (mesh) {
      EXPECT_EQ(back.assets[0].path, "meshes/hollow-d6.obj");
      EXPECT_NE(back.assets[0].text.find("v "), std::string::npos);
    }
    const dicesim::DieModel rebuilt = w::compile_spec(back);
    EXPECT_EQ(w::model_fingerprint(rebuilt), spec.fingerprint) << rel;
    EXPECT_EQ(rebuilt.outcome_labels, direct.outcome_labels);
  }
  // A mesh named by --set (relative to the user's folder) is carried too.
  const std::string d6 = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/hollow-d6.toml";
  const std::string obj = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/meshes/hollow-d6.obj";
  const std::vector<std::string> set = {"die.mesh=\"" + obj + "\""};
  const dicesim::DieModel direct = dicesim::compile(dicesim::load_scene(d6, set), d6);
  const w::RunSpec spec = w::make_run_spec(4, d6, set, direct, 1, 10);
  ASSERT_EQ(spec.assets.size(), 1u);
  EXPECT_EQ(w::model_fingerprint(w::compile_spec(w::from_message(w::to_message(spec)))), spec.fingerprint);
}

// The wire's bounds (1..120 outcomes, labels in [0, 999]): a die beyond them is bad input when the
// run is made, and a message that claims more is not decoded (its receiver counts it).
TEST(LcmWire, OutcomeBoundsAreCheckedOnBothSides) {
  EXPECT_TRUE(w::valid_outcome_labels({0, 7, 999}));
  EXPECT_FALSE(w::valid_outcome_labels({}));
  EXPECT_FALSE(w::valid_outcome_labels({1, 1000}));
  EXPECT_FALSE(w::valid_outcome_labels({-1, 2}));
  EXPECT_FALSE(w::valid_outcome_labels({2, 1}));
  std::vector<std::int32_t> many(121);
  for (std::size_t i = 0; i < many.size(); ++i) many[i] = static_cast<std::int32_t>(i);
  EXPECT_FALSE(w::valid_outcome_labels(many));
  many.pop_back();
  EXPECT_TRUE(w::valid_outcome_labels(many));

  auto answer = [](int n) {
    dicesim_lcm::probabilities p{};
    p.run_id = 9;
    p.n_outcomes = n;
    for (int i = 0; i < n; ++i) p.labels.push_back(i);
    p.counts.assign(static_cast<std::size_t>(n), 1);
    p.p = p.ci_lo = p.ci_hi = std::vector<double>(static_cast<std::size_t>(n), 0.5);
    return w::encode(p);
  };
  for (int n : {1, 20, 120}) {
    const auto b = answer(n);
    const auto d = w::decode<dicesim_lcm::probabilities>(b.data(), b.size());
    ASSERT_TRUE(d.has_value()) << n;
    EXPECT_EQ(d->labels.size(), static_cast<std::size_t>(n));
  }
  for (int n : {0, 121, 127}) {
    const auto b = answer(n);
    EXPECT_FALSE(w::decode<dicesim_lcm::probabilities>(b.data(), b.size()).has_value()) << n;
  }
  // A count far beyond the bytes: rejected before anything is allocated.
  auto huge = answer(3);
  huge[24] = 0x7f;
  EXPECT_FALSE(w::decode<dicesim_lcm::probabilities>(huge.data(), huge.size()).has_value());

  const std::string d20 = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/d20.toml";
  const dicesim::DieModel m = dicesim::compile(dicesim::load_scene(d20), d20);
  w::RunSpec spec = w::make_run_spec(5, d20, {}, m, 1, 10);
  spec.labels = std::vector<int>(many.begin(), many.end());
  spec.labels.push_back(500);  // 121
  auto b = w::encode(w::to_message(spec));
  EXPECT_FALSE(w::decode<dicesim_lcm::run_start>(b.data(), b.size()).has_value());
  spec.labels.pop_back();
  b = w::encode(w::to_message(spec));
  EXPECT_TRUE(w::decode<dicesim_lcm::run_start>(b.data(), b.size()).has_value());

  // A die with more outcomes than the wire carries: bad input naming the scene, before any run.
  const std::string prism = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/prism3.toml";
  const dicesim::DieModel many_sides = dicesim::compile(dicesim::load_scene(prism, {"die.sides=130"}), prism);
  ASSERT_GT(many_sides.outcomes(), 120);
  try {
    w::check_wire_outcomes(many_sides, prism);
    FAIL() << "a die with " << many_sides.outcomes() << " outcomes passed";
  } catch (const dicesim::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("120"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(prism), std::string::npos) << e.what();
  }
  EXPECT_THROW(w::make_run_spec(6, prism, {"die.sides=130"}, many_sides, 1, 10), dicesim::SceneError);
}

// Logs and checkpoints of the six-outcome wire are recognised by their LCM type hashes.
TEST(LcmWire, SixOutcomeWireMessagesAreRecognisedAsTheOldFormat) {
  const std::uint8_t old_batch[] = {0x51, 0x96, 0xdd, 0x2e, 0x39, 0x1c, 0xfd, 0x23, 0, 0};
  ASSERT_NE(w::legacy_format(old_batch, sizeof old_batch), nullptr);
  EXPECT_NE(std::string(w::legacy_format(old_batch, sizeof old_batch)).find("toss_batch"), std::string::npos);
  const auto now = w::encode(sample_batch(3));
  EXPECT_EQ(w::legacy_format(now.data(), now.size()), nullptr);
  EXPECT_FALSE(w::decode<dicesim_lcm::toss_batch>(old_batch, sizeof old_batch).has_value());
  // The wire whose corrections had four kinds (before issue 39): its toss_batch and probabilities.
  const std::uint8_t four_batch[] = {0xa7, 0x77, 0x92, 0x31, 0x07, 0x88, 0x5c, 0xfe, 0, 0};
  const std::uint8_t four_prob[] = {0x76, 0x37, 0x22, 0x94, 0x5a, 0xbe, 0x87, 0x78, 0, 0};
  ASSERT_NE(w::legacy_format(four_batch, sizeof four_batch), nullptr);
  EXPECT_NE(std::string(w::legacy_format(four_batch, sizeof four_batch)).find("four-corrections"), std::string::npos);
  ASSERT_NE(w::legacy_format(four_prob, sizeof four_prob), nullptr);
  EXPECT_NE(std::string(w::legacy_format(four_prob, sizeof four_prob)).find("corrections[4]"), std::string::npos);
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

// LCM's tcpq provider does not look names up (podman kube play of examples/kubernetes/live-run.yaml:
// every worker's connect to tcpq://dicesim-hub:7700 was refused, tcpq://ADDRESS:7700 worked).
TEST(LcmWire, TcpqHostNamesBecomeAddresses) {
  EXPECT_EQ(w::resolve_url("tcpq://localhost:7700"), "tcpq://127.0.0.1:7700");  // /etc/hosts, no DNS
  ::setenv("LCM_DEFAULT_URL", "tcpq://localhost:7701", 1);
  EXPECT_EQ(w::resolve_url(""), "tcpq://127.0.0.1:7701");
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(w::resolve_url("tcpq://127.0.0.1:7700"), "tcpq://127.0.0.1:7700");
}
