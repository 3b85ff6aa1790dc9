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

/// Empty if `name` may name an account (1 to 63 characters, no control characters, no ':'),
/// else what is wrong with it.
std::string check_account_name(const std::string& name);

/// The accounts of a file (see above). Throws std::runtime_error naming the file, the entry and
/// what is wrong: not YAML, no accounts, a name missing, repeated or invalid, an unknown role, a
/// password that is not a salted hash (a password in clear is refused).
std::map<std::string, Account> load_accounts(const std::string& path);

/// Checks HTTP Basic credentials against the accounts. Thread-safe; one key derivation at a
/// time (a flood of wrong passwords costs at most one core).
class Authenticator {
 public:
  explicit Authenticator(std::map<std::string, Account> accounts);
  /// The account an Authorization header value ("Basic base64(name:password)") proves, if any.
  std::optional<Account> check(const std::string& authorization);
  std::size_t size() const { return accounts_.size(); }

  static constexpr std::size_t kRemembered = 256;

 private:
  std::map<std::string, Account> accounts_;
  std::mutex m_;
  std::map<std::string, std::string> verified_;  ///< SHA-256 of a header value -> account name
};

/// An account entry for the accounts file, as `usv-fdi dashboard-account` prints it.
std::string account_entry(const std::string& name, Role role, const std::string& password_hash);

}  // namespace usvfdi::app::dashboard
