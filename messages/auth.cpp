#include "messages/auth.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/params.h>

namespace dicesim::wire {
namespace {

constexpr std::uint8_t kMagic[4] = {'D', 'S', 'M', '1'};

std::string octal(unsigned mode) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", mode & 07777u);
  return buf;
}

}  // namespace

std::vector<std::uint8_t> parse_key_text(const std::string& text, const std::string& path) {
  std::string hex;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) continue;
    if (!std::isxdigit(static_cast<unsigned char>(c)))
      throw KeyError("key file '" + path + "': character '" + std::string(1, c) +
                     "' is not a hex digit (allowed: 0-9 a-f A-F and whitespace; make one with "
                     "`(umask 077; openssl rand -hex 32 > FILE)`)");
    hex += c;
  }
  if (hex.size() % 2 != 0)
    throw KeyError("key file '" + path + "': " + std::to_string(hex.size()) + " hex digits, an odd number (allowed: an even number, at least " +
                   std::to_string(2 * kMinKeyBytes) + ")");
  if (hex.size() < 2 * kMinKeyBytes || hex.size() > 2 * kMaxKeyBytes)
    throw KeyError("key file '" + path + "': " + std::to_string(hex.size() / 2) + " bytes of key (allowed: " +
                   std::to_string(kMinKeyBytes) + " to " + std::to_string(kMaxKeyBytes) + " bytes, i.e. at least " +
                   std::to_string(2 * kMinKeyBytes) + " hex digits)");
  std::vector<std::uint8_t> key(hex.size() / 2);
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(std::stoi(hex.substr(2 * i, 2), nullptr, 16));
  return key;
}

std::vector<std::uint8_t> load_key_file(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw KeyError("key file '" + path + "': " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw KeyError("key file '" + path + "' is not a regular file");
  if ((st.st_mode & 077) != 0)
    throw KeyError("key file '" + path + "' has mode " + octal(st.st_mode) +
                   ": group or others may access it (allowed: 0600 or 0400; chmod 600 '" + path + "')");
  if (st.st_uid != geteuid() && st.st_uid != 0)
    throw KeyError("key file '" + path + "' is owned by uid " + std::to_string(st.st_uid) +
                   " (allowed: this user, uid " + std::to_string(geteuid()) + ", or root)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw KeyError("key file '" + path + "': cannot open: " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  if (s.str().size() > 16 * kMaxKeyBytes) throw KeyError("key file '" + path + "' is too large to be a key");
  return parse_key_text(s.str(), path);
}

bool looks_sealed(const void* data, std::size_t len) {
  return len >= kSealSize &&
         std::memcmp(static_cast<const std::uint8_t*>(data) + len - kSealSize, kMagic, sizeof kMagic) == 0;
}

struct Sealer::Impl {
  EVP_MAC* mac = nullptr;
  EVP_MAC_CTX* ctx = nullptr;
  ~Impl() {
    EVP_MAC_CTX_free(ctx);
    EVP_MAC_free(mac);
  }
};

Sealer::Sealer(const std::vector<std::uint8_t>& key) {
  if (key.empty()) return;
  auto impl = std::make_unique<Impl>();
  impl->mac = EVP_MAC_fetch(nullptr, "HMAC", nullptr);
  if (impl->mac) impl->ctx = EVP_MAC_CTX_new(impl->mac);
  char digest[] = "SHA256";
  const OSSL_PARAM params[] = {OSSL_PARAM_construct_utf8_string(OSSL_MAC_PARAM_DIGEST, digest, 0), OSSL_PARAM_construct_end()};
  if (!impl->ctx || EVP_MAC_init(impl->ctx, key.data(), key.size(), params) != 1)
    throw std::runtime_error("OpenSSL: cannot set up HMAC-SHA-256");
  impl_ = std::move(impl);
}

Sealer::Sealer() = default;
Sealer::~Sealer() = default;
Sealer::Sealer(Sealer&&) noexcept = default;
Sealer& Sealer::operator=(Sealer&&) noexcept = default;

void Sealer::tag(std::string_view channel, const std::uint8_t* data, std::size_t len, std::uint8_t* out) {
  // Re-initialising with no key keeps the key given at construction (OpenSSL 3 HMAC).
  const std::uint8_t clen[4] = {static_cast<std::uint8_t>(channel.size() >> 24), static_cast<std::uint8_t>(channel.size() >> 16),
                                static_cast<std::uint8_t>(channel.size() >> 8), static_cast<std::uint8_t>(channel.size())};
  std::size_t n = 0;
  if (EVP_MAC_init(impl_->ctx, nullptr, 0, nullptr) != 1 || EVP_MAC_update(impl_->ctx, clen, sizeof clen) != 1 ||
      EVP_MAC_update(impl_->ctx, reinterpret_cast<const unsigned char*>(channel.data()), channel.size()) != 1 ||
      EVP_MAC_update(impl_->ctx, data, len) != 1 || EVP_MAC_update(impl_->ctx, kMagic, sizeof kMagic) != 1 ||
      EVP_MAC_final(impl_->ctx, out, &n, kMacSize) != 1 || n != kMacSize)
    throw std::runtime_error("OpenSSL: HMAC-SHA-256 failed");
}

void Sealer::seal(std::string_view channel, std::vector<std::uint8_t>& bytes) {
  if (!impl_) return;
  const std::size_t len = bytes.size();
  bytes.resize(len + kSealSize);
  std::memcpy(bytes.data() + len, kMagic, sizeof kMagic);
  tag(channel, bytes.data(), len, bytes.data() + len + sizeof kMagic);
}

std::optional<std::size_t> Sealer::open(std::string_view channel, const void* data, std::size_t len) {
  if (!impl_) return len;
  if (!looks_sealed(data, len)) return std::nullopt;
  const auto* p = static_cast<const std::uint8_t*>(data);
  const std::size_t payload = len - kSealSize;
  std::uint8_t want[kMacSize];
  tag(channel, p, payload, want);
  if (CRYPTO_memcmp(want, p + payload + sizeof kMagic, kMacSize) != 0) return std::nullopt;
  return payload;
}

}  // namespace dicesim::wire
