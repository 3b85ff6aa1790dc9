// The dashboard's accounts (issue 13, section 1): who may see the fleet board and who may
// acknowledge. A YAML file lists each account's name, role and password, the password stored
// only as a salted PBKDF2-HMAC-SHA256 hash (OpenSSL), never in clear:
//
//   accounts:
//     - name: alice
//       role: operator          # may acknowledge
//       password: pbkdf2-sha256$600000$<salt, base64>$<hash, base64>
//     - name: bob
//       role: observer          # sees the board, cannot acknowledge
//       password: pbkdf2-sha256$...
//
// `usv-fdi dashboard-account NAME --role ROLE` reads a password on stdin and prints such an entry.
// Browsers authenticate with HTTP Basic (RFC 7617); an Authorization value verified once is
// remembered by its SHA-256 (a bounded set), so that the page's requests do not each pay for the
// key derivation. No HTTP or DDS here.
#pragma once

#include <cstddef>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace usvfdi::app::dashboard {

enum class Role { kObserver, kOperator };
const char* to_string(Role r);

struct Account {
  std::string name;
  Role role = Role::kObserver;
  std::string password_hash;  ///< "pbkdf2-sha256$ITERATIONS$SALT$HASH"
};

constexpr unsigned kDefaultIterations = 600000;

/// A new salted hash of `password` in the stored form (16 random bytes of salt).
std::string hash_password(const std::string& password, unsigned iterations = kDefaultIterations);
/// True if `password` is the one `stored` was made from; false for a wrong password. Throws
/// std::invalid_argument naming what is wrong when `stored` is not a hash of that form.
bool verify_password(const std::string& password, const std::string& stored);
/// Empty if `stored` is a well-formed hash, else what is wrong with it.
std::string check_password_hash(const std::string& stored);

/// Empty if `name` may name an account, else what is wrong with it: valid UTF-8 of 1 to 63 bytes,
/// no control characters (C0, DEL, C1), no ':', no invisible or direction-changing characters
/// (format characters, line and paragraph separators), no space at either end; so that the name
/// in "acknowledged by <name>" reads as what it is.
std::string check_account_name(const std::string& name);

/// The accounts of a file (see above). Throws std::runtime_error naming the file, the entry and
/// what is wrong: not YAML, no accounts, a name missing, repeated or invalid, an unknown role, a
/// password that is not a salted hash (a password in clear is refused).
std::map<std::string, Account> load_accounts(const std::string& path);

/// Checks HTTP Basic credentials against the accounts. Thread-safe. A credential verified once
/// is remembered by its HMAC-SHA256 under a key made at start (the oldest forgotten first), and
/// found without waiting for any key derivation; derivations run one at a time, and when
/// kMaxWaiting already wait the request is turned away (busy) rather than queued, so a flood of
/// wrong passwords costs at most one core and never holds up a signed-in user.
class Authenticator {
 public:
  /// Throws std::invalid_argument if `accounts` is empty.
  explicit Authenticator(std::map<std::string, Account> accounts);

  struct Result {
    std::optional<Account> account;  ///< the account proved, if any
    bool busy = false;               ///< not checked: too many derivations waiting
    std::string tried;               ///< the name the credentials gave ("" if none could be read)
  };
  /// What an Authorization header value ("Basic base64(name:password)") proves.
  Result authenticate(const std::string& authorization);
  /// The account it proves, if any (busy counts as none).
  std::optional<Account> check(const std::string& authorization) {
    return authenticate(authorization).account;
  }
  std::size_t size() const { return accounts_.size(); }

  static constexpr std::size_t kRemembered = 256;
  static constexpr int kMaxWaiting = 4;

 private:
  std::string key_of(const std::string& authorization) const;

  std::map<std::string, Account> accounts_;
  std::string dummy_hash_;  ///< checked for an unknown name: as slow as the slowest account
  std::string hmac_key_;
  std::mutex m_;                                 ///< verified_, order_, waiting_
  std::map<std::string, std::string> verified_;  ///< HMAC of a header value -> account name
  std::deque<std::string> order_;                ///< verified_'s keys, oldest first
  int waiting_ = 0;
  std::mutex derive_m_;  ///< one key derivation at a time
};

/// An account entry for the accounts file, as `usv-fdi dashboard-account` prints it.
std::string account_entry(const std::string& name, Role role, const std::string& password_hash);

}  // namespace usvfdi::app::dashboard
