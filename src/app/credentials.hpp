// When this process's DDS Security credentials stop being valid. Fast DDS 2.9 checks the identity
// certificate and the permissions grant at the handshake only: a session already open keeps
// working after either expires, and it offers no hook for a peer's expiry. So every usv-fdi
// process watches its own credentials and leaves the domain when the first of them expires (a
// peer whose credentials expire does the same on its side). No Fast DDS in this header.
#pragma once

#include <limits>
#include <string>

namespace usvfdi::app {

struct CredentialExpiry {
  /// Unix time [s] after which the first credential is no longer valid (inf: none expires, e.g.
  /// a participant without DDS Security).
  double not_after = std::numeric_limits<double>::infinity();
  std::string what;  ///< which one and where ("identity certificate /x/cert.pem"), "" if none

  bool secure() const { return !what.empty(); }
  /// True once `now` (unix s) is past not_after.
  bool expired(double now) const { return now > not_after; }
};

/// The earliest expiry among the identity CA, the identity certificate (notAfter) and the
/// permissions grant (<not_after>) named by the participant profile `profile` (the XML profiles
/// must be loaded). Throws std::runtime_error naming the file if one cannot be read or parsed.
CredentialExpiry credential_expiry(const std::string& profile);

/// The notAfter of the first certificate of a PEM file [unix s]; throws naming the file.
double certificate_not_after(const std::string& pem_path);
/// The <not_after> of the grant in a permissions document (XML, or its S/MIME-signed .p7s, whose
/// text carries the XML) [unix s, the time is UTC]; throws naming the file.
double grant_not_after(const std::string& permissions_path);

/// "credentials expired: the identity certificate /x/cert.pem is not valid after
/// 2026-12-01T22:15:03Z: leaving the DDS domain (restart with renewed credentials)".
std::string expired_message(const CredentialExpiry& e);
/// "DDS Security credentials valid until ... (first to expire: ...)", "" without security.
std::string validity_message(const CredentialExpiry& e);

}  // namespace usvfdi::app
