#include "credentials.hpp"

#include "usv_fdi/core/text.hpp"

#include <openssl/asn1.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace usvfdi::app {

namespace {

std::string file_of(const std::string& uri) {
  const std::string scheme = "file://";
  return uri.compare(0, scheme.size(), scheme) == 0 ? uri.substr(scheme.size()) : uri;
}

}  // namespace

double certificate_not_after(const std::string& pem_path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(pem_path.c_str(), "r"), &std::fclose);
  if (!f) throw std::runtime_error(pem_path + ": cannot open the certificate");
  std::unique_ptr<X509, void (*)(X509*)> cert(PEM_read_X509(f.get(), nullptr, nullptr, nullptr),
                                              &X509_free);
  if (!cert) throw std::runtime_error(pem_path + ": not a PEM certificate");
  std::tm tm{};
  if (ASN1_TIME_to_tm(X509_get0_notAfter(cert.get()), &tm) != 1) {
    throw std::runtime_error(pem_path + ": cannot read the certificate's notAfter");
  }
  return static_cast<double>(timegm(&tm));
}

double grant_not_after(const std::string& permissions_path) {
  std::ifstream in(permissions_path, std::ios::binary);
  if (!in) throw std::runtime_error(permissions_path + ": cannot open the permissions");
  std::ostringstream os;
  os << in.rdbuf();
  const std::string text = os.str();
  const std::string open = "<not_after>", close = "</not_after>";
  const std::size_t a = text.find(open);
  const std::size_t b = a == std::string::npos ? a : text.find(close, a);
  if (b == std::string::npos) {
    throw std::runtime_error(permissions_path + ": no <not_after> in the permissions grant");
  }
  const std::string value = text.substr(a + open.size(), b - a - open.size());
  std::tm tm{};
  const char* end = strptime(value.c_str(), "%Y-%m-%dT%H:%M:%S", &tm);
  if (end == nullptr) {
    throw std::runtime_error(permissions_path + ": <not_after> '" + value +
                             "' is not YYYY-MM-DDTHH:MM:SS");
  }
  return static_cast<double>(timegm(&tm));
}

CredentialExpiry credential_expiry(const std::string& profile) {
  namespace fdds = eprosima::fastdds::dds;
  CredentialExpiry out;
  fdds::DomainParticipantQos qos;
  if (fdds::DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(
          profile, qos) != ReturnCode_t::RETCODE_OK) {
    return out;  // the participant was made from it: cannot happen; then: nothing to watch
  }
  const auto take = [&out](double t, const std::string& what) {
    if (t < out.not_after || out.what.empty()) {
      out.not_after = t;
      out.what = what;
    }
  };
  for (const auto& p : qos.properties().properties()) {
    const std::string& n = p.name();
    if (n == "dds.sec.auth.builtin.PKI-DH.identity_certificate") {
      const std::string path = file_of(p.value());
      take(certificate_not_after(path), "identity certificate " + path);
    } else if (n == "dds.sec.auth.builtin.PKI-DH.identity_ca") {
      const std::string path = file_of(p.value());
      take(certificate_not_after(path), "identity CA " + path);
    } else if (n == "dds.sec.access.builtin.Access-Permissions.permissions") {
      const std::string path = file_of(p.value());
      take(grant_not_after(path), "permissions grant " + path);
    }
  }
  return out;
}

std::string expired_message(const CredentialExpiry& e) {
  return "credentials expired: the " + e.what + " is not valid after " + utc_text(e.not_after) +
         ": leaving the DDS domain (restart with renewed credentials)";
}

std::string validity_message(const CredentialExpiry& e) {
  if (!e.secure()) return std::string();
  return "DDS Security credentials valid until " + utc_text(e.not_after) +
         " (first to expire: the " + e.what + "); the session ends then";
}

}  // namespace usvfdi::app
