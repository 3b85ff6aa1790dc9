#include "accounts.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>
#include <vector>

namespace usvfdi::app::dashboard {
namespace {

constexpr const char* kScheme = "pbkdf2-sha256";
constexpr std::size_t kSaltBytes = 16;
constexpr std::size_t kHashBytes = 32;
constexpr unsigned kMinIterations = 1000;
constexpr unsigned kMaxIterations = 100000000;

std::string b64_encode(const unsigned char* p, std::size_t n) {
  std::string out(4 * ((n + 2) / 3), '\0');
  const int len =
      EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()), p, static_cast<int>(n));
  out.resize(static_cast<std::size_t>(len));
  return out;
}

/// Standard base64 with padding; nullopt if `s` is not that.
std::optional<std::vector<unsigned char>> b64_decode(const std::string& s) {
  if (s.empty() || s.size() % 4 != 0) return std::nullopt;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    const bool pad_ok = c == '=' && i + 2 >= s.size();
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '/' && !pad_ok) {
      return std::nullopt;
    }
  }
  std::vector<unsigned char> out(s.size() / 4 * 3);
  const int len = EVP_DecodeBlock(out.data(), reinterpret_cast<const unsigned char*>(s.data()),
                                  static_cast<int>(s.size()));
  if (len < 0) return std::nullopt;
  std::size_t n = static_cast<std::size_t>(len);
  if (s[s.size() - 1] == '=') --n;  // EVP_DecodeBlock counts the padding as zero bytes
  if (s[s.size() - 2] == '=') --n;
  out.resize(n);
  return out;
}

struct Parsed {
  unsigned iterations = 0;
  std::vector<unsigned char> salt, hash;
};

/// The parts of a stored hash, or what is wrong with it in *why.
std::optional<Parsed> parse_hash(const std::string& stored, std::string* why) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t d = stored.find('$', start);
    parts.push_back(stored.substr(start, d == std::string::npos ? std::string::npos : d - start));
    if (d == std::string::npos) break;
    start = d + 1;
  }
  if (parts.size() != 4 || parts[0] != kScheme) {
    *why = std::string("not a salted hash of the form ") + kScheme +
           "$ITERATIONS$SALT$HASH (make one with `usv-fdi dashboard-account`)";
    return std::nullopt;
  }
  Parsed p;
  try {
    std::size_t used = 0;
    const unsigned long it = std::stoul(parts[1], &used);
    if (used != parts[1].size() || parts[1][0] == '-' || it < kMinIterations ||
        it > kMaxIterations) {
      throw std::out_of_range("iterations");
    }
    p.iterations = static_cast<unsigned>(it);
  } catch (const std::exception&) {
    *why = "its iteration count '" + parts[1] + "' is not a whole number from " +
           std::to_string(kMinIterations) + " to " + std::to_string(kMaxIterations);
    return std::nullopt;
  }
  auto salt = b64_decode(parts[2]);
  auto hash = b64_decode(parts[3]);
  if (!salt || salt->size() < 8) {
    *why = "its salt is not base64 of at least 8 bytes";
    return std::nullopt;
  }
  if (!hash || hash->size() != kHashBytes) {
    *why = "its hash is not base64 of 32 bytes";
    return std::nullopt;
  }
  p.salt = std::move(*salt);
  p.hash = std::move(*hash);
  return p;
}

std::vector<unsigned char> derive(const std::string& password,
                                  const std::vector<unsigned char>& salt, unsigned iterations) {
  std::vector<unsigned char> out(kHashBytes);
  if (PKCS5_PBKDF2_HMAC(password.data(), static_cast<int>(password.size()), salt.data(),
                        static_cast<int>(salt.size()), static_cast<int>(iterations), EVP_sha256(),
                        static_cast<int>(out.size()), out.data()) != 1) {
    throw std::runtime_error("PBKDF2-HMAC-SHA256 failed (OpenSSL)");
  }
  return out;
}

std::string sha256_hex(const std::string& s) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(s.data(), s.size(), md, &n, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("SHA-256 failed (OpenSSL)");
  }
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < n; ++i) {
    out += hex[md[i] >> 4];
    out += hex[md[i] & 15];
  }
  return out;
}

}  // namespace

const char* to_string(Role r) { return r == Role::kOperator ? "operator" : "observer"; }

std::string hash_password(const std::string& password, unsigned iterations) {
  if (iterations < kMinIterations || iterations > kMaxIterations) {
    throw std::invalid_argument("iterations: from " + std::to_string(kMinIterations) + " to " +
                                std::to_string(kMaxIterations));
  }
  std::vector<unsigned char> salt(kSaltBytes);
  if (RAND_bytes(salt.data(), static_cast<int>(salt.size())) != 1) {
    throw std::runtime_error("no random bytes for a salt (OpenSSL RAND_bytes)");
  }
  const std::vector<unsigned char> h = derive(password, salt, iterations);
  return std::string(kScheme) + "$" + std::to_string(iterations) + "$" +
         b64_encode(salt.data(), salt.size()) + "$" + b64_encode(h.data(), h.size());
}

std::string check_password_hash(const std::string& stored) {
  std::string why;
  return parse_hash(stored, &why) ? std::string() : why;
}

bool verify_password(const std::string& password, const std::string& stored) {
  std::string why;
  const std::optional<Parsed> p = parse_hash(stored, &why);
  if (!p) throw std::invalid_argument("password hash: " + why);
  const std::vector<unsigned char> h = derive(password, p->salt, p->iterations);
  return CRYPTO_memcmp(h.data(), p->hash.data(), h.size()) == 0;
}

std::string check_account_name(const std::string& name) {
  if (name.empty() || name.size() > 63) return "a name has 1 to 63 characters";
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "control characters";
    if (c == ':') return "':' (HTTP Basic separates the name from the password with it)";
  }
  return {};
}

std::map<std::string, Account> load_accounts(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error("accounts file " + path + ": " + e.what());
  }
  const auto fail = [&path](const std::string& where, const std::string& what) {
    return std::runtime_error("accounts file " + path + ": " + where + ": " + what);
  };
  if (!root.IsMap() || !root["accounts"] || !root["accounts"].IsSequence() ||
      root["accounts"].size() == 0) {
    throw fail("top level", "expected `accounts:`, a list of {name, role, password}");
  }
  std::map<std::string, Account> out;
  std::size_t i = 0;
  for (const YAML::Node& n : root["accounts"]) {
    const std::string where =
        "account " + std::to_string(++i) + " (line " + std::to_string(n.Mark().line + 1) + ")";
    if (!n.IsMap()) throw fail(where, "expected a map {name, role, password}");
    for (const auto& kv : n) {
      const std::string k = kv.first.as<std::string>();
      if (k != "name" && k != "role" && k != "password") {
        throw fail(where, "unknown key '" + k + "' (name, role, password)");
      }
    }
    Account a;
    if (!n["name"] || !n["name"].IsScalar()) throw fail(where, "name is missing");
    a.name = n["name"].as<std::string>();
    if (const std::string why = check_account_name(a.name); !why.empty()) {
      throw fail(where, "name '" + a.name + "': " + why);
    }
    const std::string who = where + ", '" + a.name + "'";
    if (!n["role"] || !n["role"].IsScalar()) throw fail(who, "role is missing");
    const std::string role = n["role"].as<std::string>();
    if (role == "operator") {
      a.role = Role::kOperator;
    } else if (role == "observer") {
      a.role = Role::kObserver;
    } else {
      throw fail(who, "role '" + role + "': expected operator or observer");
    }
    if (!n["password"] || !n["password"].IsScalar()) throw fail(who, "password is missing");
    a.password_hash = n["password"].as<std::string>();
    if (const std::string why = check_password_hash(a.password_hash); !why.empty()) {
      throw fail(who, "password: " + why + "; a password in clear is never accepted");
    }
    if (out.count(a.name) > 0) throw fail(who, "the name is given twice");
    out[a.name] = a;
  }
  return out;
}

Authenticator::Authenticator(std::map<std::string, Account> accounts)
    : accounts_(std::move(accounts)) {}

std::optional<Account> Authenticator::check(const std::string& authorization) {
  // "Basic" is case-insensitive (RFC 7617); one space, then base64(name:password).
  if (authorization.size() < 7) return std::nullopt;
  std::string scheme = authorization.substr(0, 6);
  std::transform(scheme.begin(), scheme.end(), scheme.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (scheme != "basic ") return std::nullopt;
  const std::string key = sha256_hex(authorization);
  std::lock_guard<std::mutex> l(m_);
  if (const auto it = verified_.find(key); it != verified_.end()) {
    return accounts_.at(it->second);
  }
  const auto raw = b64_decode(authorization.substr(6));
  if (!raw) return std::nullopt;
  const std::string pair(raw->begin(), raw->end());
  const std::size_t colon = pair.find(':');
  if (colon == std::string::npos) return std::nullopt;
  const std::string name = pair.substr(0, colon), password = pair.substr(colon + 1);
  const auto it = accounts_.find(name);
  if (it == accounts_.end()) {
    if (accounts_.empty()) return std::nullopt;
    // the same work as for a known name, so that the time taken does not tell names apart
    verify_password(password, accounts_.begin()->second.password_hash);
    return std::nullopt;
  }
  if (!verify_password(password, it->second.password_hash)) return std::nullopt;
  if (verified_.size() >= kRemembered) verified_.clear();
  verified_[key] = name;
  return it->second;
}

std::string account_entry(const std::string& name, Role role, const std::string& password_hash) {
  // A name is quoted as YAML's double-quoted scalar (it may hold any printable character).
  std::string q = "\"";
  for (const char c : name) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  q += '"';
  return "  - name: " + q + "\n    role: " + to_string(role) + "\n    password: \"" +
         password_hash + "\"\n";
}

}  // namespace usvfdi::app::dashboard
