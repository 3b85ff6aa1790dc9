#include "accounts.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>
#include <vector>

#include "usv_fdi/core/text.hpp"

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
  // Canonical only: '=' as trailing padding alone, zero padding bits (one text per value).
  if (b64_encode(out.data(), out.size()) != s) return std::nullopt;
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
    if (parts[1].empty() || parts[1].find_first_not_of("0123456789") != std::string::npos) {
      throw std::invalid_argument("iterations");
    }
    const unsigned long it = std::stoul(parts[1], &used);
    if (it < kMinIterations || it > kMaxIterations) throw std::out_of_range("iterations");
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

/// The code point of the UTF-8 sequence at s[*i] (advancing *i), -1 if it is not valid UTF-8
/// (overlong forms, surrogates and values past U+10FFFF included).
long next_code_point(const std::string& s, std::size_t* i) {
  unsigned cp = 0;
  const std::size_t n = utf8_sequence(s, *i, &cp);
  if (n == 0) return -1;
  *i += n;
  return static_cast<long>(cp);
}

/// Characters that change how the rest of a line reads or do not show: C1 controls, soft hyphen,
/// zero-width and direction marks, line/paragraph separators, embeddings and isolates, the BOM.
bool invisible(long cp) {
  return (cp >= 0x80 && cp <= 0x9F) || cp == 0xAD || cp == 0x061C || cp == 0x180E ||
         (cp >= 0x200B && cp <= 0x200F) || (cp >= 0x2028 && cp <= 0x202E) ||
         (cp >= 0x2060 && cp <= 0x206F) || cp == 0xFEFF || (cp >= 0xFFF9 && cp <= 0xFFFB);
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
  if (name.empty() || name.size() > 63) return "a name has 1 to 63 bytes (UTF-8)";
  if (name.front() == ' ' || name.back() == ' ') return "a space at its start or end";
  for (std::size_t i = 0; i < name.size();) {
    const long cp = next_code_point(name, &i);
    if (cp < 0) return "not valid UTF-8";
    if (cp < 0x20 || cp == 0x7f) return "control characters";
    if (cp == ':') return "':' (HTTP Basic separates the name from the password with it)";
    if (invisible(cp)) return "an invisible or direction-changing character";
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
    std::set<std::string> keys;
    for (const auto& kv : n) {
      const std::string k = kv.first.as<std::string>();
      if (k != "name" && k != "role" && k != "password") {
        throw fail(where, "unknown key '" + k + "' (name, role, password)");
      }
      if (!keys.insert(k).second) throw fail(where, "'" + k + "' is given twice");
      if (!kv.second.IsScalar()) throw fail(where, k + " must be a text value");
    }
    Account a;
    if (!n["name"]) throw fail(where, "name is missing");
    a.name = n["name"].as<std::string>();
    if (const std::string why = check_account_name(a.name); !why.empty()) {
      throw fail(where, "name '" + a.name + "': " + why);
    }
    const std::string who = where + ", '" + a.name + "'";
    if (!n["role"]) throw fail(who, "role is missing");
    const std::string role = n["role"].as<std::string>();
    if (role == "operator") {
      a.role = Role::kOperator;
    } else if (role == "observer") {
      a.role = Role::kObserver;
    } else {
      throw fail(who, "role '" + role + "': expected operator or observer");
    }
    if (!n["password"]) throw fail(who, "password is missing");
    a.password_hash = n["password"].as<std::string>();
    if (const std::string why = check_password_hash(a.password_hash); !why.empty()) {
      const bool clear = a.password_hash.rfind(std::string(kScheme) + "$", 0) != 0;
      throw fail(who, "password: " + why +
                          (clear ? "; a password in clear is never accepted" : std::string()));
    }
    if (out.count(a.name) > 0) throw fail(who, "the name is given twice");
    out[a.name] = a;
  }
  return out;
}

Authenticator::Authenticator(std::map<std::string, Account> accounts)
    : accounts_(std::move(accounts)) {
  if (accounts_.empty()) throw std::invalid_argument("no accounts");
  // An unknown name costs what the slowest account costs: the time does not tell names apart.
  unsigned slowest = kMinIterations;
  for (const auto& [name, a] : accounts_) {
    std::string why;
    if (const auto p = parse_hash(a.password_hash, &why))
      slowest = std::max(slowest, p->iterations);
  }
  dummy_hash_ = hash_password("not a password of any account", slowest);
  unsigned char key[32];
  if (RAND_bytes(key, sizeof key) != 1) throw std::runtime_error("no random bytes (OpenSSL)");
  hmac_key_.assign(reinterpret_cast<const char*>(key), sizeof key);
}

std::string Authenticator::key_of(const std::string& authorization) const {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (HMAC(EVP_sha256(), hmac_key_.data(), static_cast<int>(hmac_key_.size()),
           reinterpret_cast<const unsigned char*>(authorization.data()), authorization.size(), md,
           &n) == nullptr) {
    throw std::runtime_error("HMAC-SHA256 failed (OpenSSL)");
  }
  return std::string(reinterpret_cast<const char*>(md), n);
}

Authenticator::Result Authenticator::authenticate(const std::string& authorization) {
  Result out;
  // "Basic" is case-insensitive (RFC 7617), then one or more spaces, then base64(name:password).
  if (authorization.size() < 7) return out;
  std::string scheme = authorization.substr(0, 6);
  std::transform(scheme.begin(), scheme.end(), scheme.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (scheme != "basic ") return out;
  const std::size_t start = authorization.find_first_not_of(' ', 6);
  if (start == std::string::npos) return out;
  const auto raw = b64_decode(authorization.substr(start));
  if (!raw) return out;
  const std::string pair(raw->begin(), raw->end());
  const std::size_t colon = pair.find(':');
  if (colon == std::string::npos) return out;
  out.tried = pair.substr(0, colon);
  const std::string password = pair.substr(colon + 1);
  const std::string key = key_of(authorization);
  {
    std::lock_guard<std::mutex> l(m_);
    if (const auto it = verified_.find(key); it != verified_.end()) {
      out.account = accounts_.at(it->second);
      return out;
    }
    if (waiting_ >= kMaxWaiting) {
      out.busy = true;
      return out;
    }
    ++waiting_;
  }
  bool ok = false;
  const auto it = accounts_.find(out.tried);
  try {
    std::lock_guard<std::mutex> one(derive_m_);
    ok =
        verify_password(password, it == accounts_.end() ? dummy_hash_ : it->second.password_hash) &&
        it != accounts_.end();
  } catch (...) {
    std::lock_guard<std::mutex> l(m_);
    --waiting_;
    throw;
  }
  std::lock_guard<std::mutex> l(m_);
  --waiting_;
  if (!ok) return out;
  if (verified_.emplace(key, out.tried).second) {
    order_.push_back(key);
    while (order_.size() > kRemembered) {
      verified_.erase(order_.front());
      order_.pop_front();
    }
  }
  out.account = it->second;
  return out;
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
