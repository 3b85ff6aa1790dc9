// The dashboard's accounts (src/app/dashboard/accounts.cpp): salted PBKDF2 hashes, the accounts
// file's checks, HTTP Basic credentials. The signed-in dashboard over HTTPS is tested in a real
// browser (tests/dashboard).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dashboard/accounts.hpp"

namespace usvfdi::app::dashboard {
namespace {

constexpr unsigned kFast = 1000;  // the fewest iterations allowed: fast tests

std::string basic(const std::string& name_password) {
  // base64 by hand for the test's few fixed strings (RFC 4648 alphabet)
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  const auto& s = name_password;
  for (; i + 2 < s.size(); i += 3) {
    const unsigned v = (unsigned(static_cast<unsigned char>(s[i])) << 16) |
                       (unsigned(static_cast<unsigned char>(s[i + 1])) << 8) |
                       static_cast<unsigned char>(s[i + 2]);
    for (int k = 3; k >= 0; --k) out += t[(v >> (6 * k)) & 63];
  }
  if (s.size() - i == 1) {
    const unsigned v = unsigned(static_cast<unsigned char>(s[i])) << 16;
    out += std::string{t[(v >> 18) & 63], t[(v >> 12) & 63], '=', '='};
  } else if (s.size() - i == 2) {
    const unsigned v = (unsigned(static_cast<unsigned char>(s[i])) << 16) |
                       (unsigned(static_cast<unsigned char>(s[i + 1])) << 8);
    out += std::string{t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return "Basic " + out;
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "usv_fdi_accounts_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(DashboardAccounts, APasswordIsStoredSaltedAndVerified) {
  const std::string h1 = hash_password("correct horse", kFast);
  const std::string h2 = hash_password("correct horse", kFast);
  EXPECT_EQ(h1.rfind("pbkdf2-sha256$1000$", 0), 0u) << h1;
  EXPECT_NE(h1, h2) << "a fresh salt per hash";
  EXPECT_EQ(h1.find("correct"), std::string::npos);
  EXPECT_TRUE(verify_password("correct horse", h1));
  EXPECT_TRUE(verify_password("correct horse", h2));
  EXPECT_FALSE(verify_password("correct hors", h1));
  EXPECT_FALSE(verify_password("", h1));
  EXPECT_EQ(check_password_hash(h1), "");
  // the default strength
  EXPECT_EQ(hash_password("x").rfind("pbkdf2-sha256$600000$", 0), 0u);
}

TEST(DashboardAccounts, AMalformedHashIsNamedNotAccepted) {
  EXPECT_NE(check_password_hash("correct horse"), "");
  EXPECT_NE(check_password_hash("pbkdf2-sha256$10$AAAAAAAAAAA=$" + std::string(44, 'A')), "");
  EXPECT_NE(check_password_hash("pbkdf2-sha256$1000$AAAAAAAAAAA=$AAAA"), "");
  EXPECT_NE(check_password_hash("pbkdf2-sha256$1000$!!!!$" + std::string(43, 'A') + "="), "");
  EXPECT_THROW(verify_password("x", "md5$abc"), std::invalid_argument);
  // the tampered hash of a real password no longer verifies it
  std::string h = hash_password("correct horse", kFast);
  h[h.size() - 3] = h[h.size() - 3] == 'A' ? 'B' : 'A';
  EXPECT_FALSE(verify_password("correct horse", h));
}

TEST(DashboardAccounts, TheAccountsFileIsCheckedEntryByEntry) {
  const std::string ok = hash_password("correct horse", kFast);
  const std::string good =
      write_file("good.yaml", "accounts:\n" + account_entry("alice", Role::kOperator, ok) +
                                  account_entry("bob \"the\" observer", Role::kObserver, ok));
  const auto acc = load_accounts(good);
  ASSERT_EQ(acc.size(), 2u);
  EXPECT_EQ(acc.at("alice").role, Role::kOperator);
  EXPECT_EQ(acc.at("bob \"the\" observer").role, Role::kObserver);

  const auto error_of = [](const std::string& name, const std::string& text) {
    try {
      load_accounts(write_file(name, text));
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(
      error_of("clear.yaml", "accounts:\n  - {name: alice, role: operator, password: hunter22}\n")
          .find("account 1 (line 2), 'alice': password: not a salted hash"),
      std::string::npos);
  EXPECT_NE(error_of("role.yaml", "accounts:\n  - {name: a, role: admin, password: '" + ok + "'}\n")
                .find("role 'admin': expected operator or observer"),
            std::string::npos);
  EXPECT_NE(error_of("twice.yaml", "accounts:\n" + account_entry("a", Role::kOperator, ok) +
                                       account_entry("a", Role::kObserver, ok))
                .find("account 2 (line 5), 'a': the name is given twice"),
            std::string::npos);
  EXPECT_NE(error_of("colon.yaml", "accounts:\n" + account_entry("a:b", Role::kOperator, ok))
                .find("name 'a:b'"),
            std::string::npos);
  EXPECT_NE(
      error_of("key.yaml", "accounts:\n  - {name: a, role: operator, pasword: '" + ok + "'}\n")
          .find("unknown key 'pasword'"),
      std::string::npos);
  EXPECT_NE(error_of("dupkey.yaml",
                     "accounts:\n  - {name: a, name: b, role: operator, password: '" + ok + "'}\n")
                .find("'name' is given twice"),
            std::string::npos);
  EXPECT_NE(
      error_of("list.yaml", "accounts:\n  - {name: [a], role: operator, password: '" + ok + "'}\n")
          .find("name must be a text value"),
      std::string::npos);
  const std::string spaced = "pbkdf2-sha256$ 1000$" + ok.substr(ok.find('$', 14) + 1);
  const std::string e = error_of(
      "iter.yaml", "accounts:\n  - {name: a, role: operator, password: '" + spaced + "'}\n");
  EXPECT_NE(e.find("iteration count ' 1000'"), std::string::npos) << e;
  EXPECT_EQ(e.find("in clear"), std::string::npos) << "a malformed hash is not a password in clear";
  EXPECT_NE(error_of("empty.yaml", "accounts: []\n").find("top level"), std::string::npos);
  EXPECT_NE(error_of("yaml.yaml", "accounts: [\n").find("accounts file"), std::string::npos);
  EXPECT_NE(error_of("missing", "").find("top level"), std::string::npos);
}

TEST(DashboardAccounts, ANameReadsAsWhatItIs) {
  EXPECT_EQ(check_account_name("alice"), "");
  EXPECT_EQ(check_account_name("Åsa Öberg"), "");
  EXPECT_EQ(check_account_name("船長 1"), "");
  EXPECT_NE(check_account_name(""), "");
  EXPECT_NE(check_account_name(std::string(64, 'a')), "");
  EXPECT_NE(check_account_name(" alice"), "");
  EXPECT_NE(check_account_name("alice "), "");
  EXPECT_NE(check_account_name("a:b"), "");
  EXPECT_NE(check_account_name("a\tb"), "");
  EXPECT_EQ(check_account_name("bad\xff utf"), "not valid UTF-8");
  EXPECT_EQ(check_account_name("\xc0\xaf"), "not valid UTF-8") << "overlong";
  EXPECT_EQ(check_account_name("a\xe2\x80"), "not valid UTF-8") << "cut short";
  EXPECT_NE(check_account_name("alice\xe2\x80\xae"), "") << "U+202E right-to-left override";
  EXPECT_NE(check_account_name("a\xe2\x80\xa8"
                               "b"),
            "")
      << "U+2028 line separator";
  EXPECT_NE(check_account_name("a\xc2\x85"
                               "b"),
            "")
      << "U+0085, a C1 control";
  EXPECT_NE(check_account_name("\xef\xbb\xbf"
                               "alice"),
            "")
      << "U+FEFF";
  EXPECT_NE(check_account_name("al\xe2\x80\x8b"
                               "ice"),
            "")
      << "U+200B zero width space";
}

TEST(DashboardAccounts, BasicCredentialsProveTheirAccountOnly) {
  std::map<std::string, Account> acc;
  acc["alice"] = {"alice", Role::kOperator, hash_password("correct horse", kFast)};
  acc["bob"] = {"bob", Role::kObserver, hash_password("battery: staple", kFast)};
  Authenticator auth(acc);
  const auto alice = auth.check(basic("alice:correct horse"));
  ASSERT_TRUE(alice.has_value());
  EXPECT_EQ(alice->name, "alice");
  EXPECT_EQ(alice->role, Role::kOperator);
  // remembered, and the same answer again
  EXPECT_EQ(auth.check(basic("alice:correct horse"))->name, "alice");
  // a password may hold ':' (only the first separates the name)
  EXPECT_EQ(auth.check(basic("bob:battery: staple"))->role, Role::kObserver);
  // the scheme's case does not matter
  EXPECT_TRUE(auth.check("bASIC " + basic("alice:correct horse").substr(6)).has_value());
  EXPECT_FALSE(auth.check(basic("alice:battery: staple")).has_value()) << "bob's password";
  EXPECT_FALSE(auth.check(basic("alice:correct horse ")).has_value());
  EXPECT_FALSE(auth.check(basic("carol:correct horse")).has_value());
  EXPECT_FALSE(auth.check(basic("alicecorrect horse")).has_value());
  EXPECT_FALSE(auth.check("").has_value());
  EXPECT_FALSE(auth.check("Bearer abc").has_value());
  EXPECT_FALSE(auth.check("Basic !!!!").has_value());
  // more than one space after the scheme is allowed (RFC 7617), base64 only in canonical form
  EXPECT_TRUE(auth.check("Basic   " + basic("alice:correct horse").substr(6)).has_value());
  std::string b = basic("ab:c");  // "YWI6Yw==": its last character holds padding bits
  ASSERT_EQ(b, "Basic YWI6Yw==");
  EXPECT_FALSE(auth.check("Basic YWI6Yx==").has_value()) << "non-zero padding bits";
  // what was tried is said, for the log
  const auto r = auth.authenticate(basic("carol:x"));
  EXPECT_FALSE(r.account.has_value());
  EXPECT_FALSE(r.busy);
  EXPECT_EQ(r.tried, "carol");
  EXPECT_THROW(Authenticator(std::map<std::string, Account>{}), std::invalid_argument);
}

TEST(DashboardAccounts, AnUnknownNameTakesAsLongAsTheSlowestAccount) {
  std::map<std::string, Account> acc;
  acc["fast"] = {"fast", Role::kOperator, hash_password("correct horse", kFast)};
  acc["slow"] = {"slow", Role::kOperator, hash_password("correct horse", 200000)};
  Authenticator auth(acc);
  using Clock = std::chrono::steady_clock;
  const auto time_of = [&](const std::string& who) {
    const auto t0 = Clock::now();
    EXPECT_FALSE(auth.check(basic(who + ":wrong password")).has_value());
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  // Medians of 3, side by side: an unknown name costs the slow account's derivation (200x the
  // fast one's), so it is never as cheap as the fast account's.
  std::vector<double> fast, unknown;
  for (int i = 0; i < 3; ++i) {
    fast.push_back(time_of("fast"));
    unknown.push_back(time_of("nobody"));
  }
  std::sort(fast.begin(), fast.end());
  std::sort(unknown.begin(), unknown.end());
  EXPECT_GT(unknown[1], 5.0 * fast[1]) << unknown[1] << " s vs " << fast[1] << " s";
}

}  // namespace
}  // namespace usvfdi::app::dashboard
