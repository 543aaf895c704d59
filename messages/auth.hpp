// Authenticated runs: every message of a run that has a key carries a trailer
//
//   payload (the LCM encoding, untouched) | "DSM1" | HMAC-SHA-256(key, channel, payload, "DSM1")
//
// so the MAC covers every byte of the message whatever its fields are (the trailer never looks
// inside the payload), and binds the channel (a batch cannot be replayed as another type). Stock
// LCM tools still decode the payload (they ignore trailing bytes); dicesim receivers with a key
// drop, and count, anything whose trailer is missing or wrong. The MAC is OpenSSL libcrypto's
// (EVP_MAC "HMAC"); tags are compared with CRYPTO_memcmp (constant time).
//
// What this does not give: confidentiality (payloads are plain), protection against denial of
// service (a flood still costs the receivers a MAC each), or any separation between holders of
// the key (any of them can forge for all). See README, "Security".
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace dicesim::wire {

inline constexpr std::size_t kMacSize = 32;               // HMAC-SHA-256
inline constexpr std::size_t kSealSize = 4 + kMacSize;    // magic + tag
inline constexpr std::size_t kMinKeyBytes = 32;           // 256 bits: 64 hex digits in the key file
inline constexpr std::size_t kMaxKeyBytes = 1024;

// A key file that cannot be used: bad input (exit 2); the message names the file and the rule.
struct KeyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A run key file: hex digits only (whitespace and newlines ignored), at least 64 of them (32
// bytes); a regular file owned by this user (or root) that group and others cannot read or write
// (mode 0600 or 0400). Make one with: (umask 077; openssl rand -hex 32 > run.key)
std::vector<std::uint8_t> load_key_file(const std::string& path);  // throws KeyError
// The rules above, applied to the file's bytes only (for tests and for messages).
std::vector<std::uint8_t> parse_key_text(const std::string& text, const std::string& path);  // throws KeyError

// Does the message end like a sealed one ("DSM1" before a 32-byte tag)? Says nothing about
// whether the tag is right: for telling a user that a run needs --key-file.
bool looks_sealed(const void* data, std::size_t len);

// Seals and opens messages with one key. An empty key means "no authentication": seal() leaves
// bytes alone and open() accepts every message whole. Holds an OpenSSL context: one per thread.
class Sealer {
 public:
  Sealer();
  explicit Sealer(const std::vector<std::uint8_t>& key);
  ~Sealer();
  Sealer(Sealer&&) noexcept;
  Sealer& operator=(Sealer&&) noexcept;
  Sealer(const Sealer&) = delete;
  Sealer& operator=(const Sealer&) = delete;

  bool enabled() const { return impl_ != nullptr; }
  // Appends the trailer to `bytes` (the encoding of a message for `channel`).
  void seal(std::string_view channel, std::vector<std::uint8_t>& bytes);
  // The payload's length if the message is authentic (always `len` when disabled), else nothing.
  std::optional<std::size_t> open(std::string_view channel, const void* data, std::size_t len);

 private:
  void tag(std::string_view channel, const std::uint8_t* data, std::size_t len, std::uint8_t* out);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dicesim::wire
