#include "sensornet/dds/security.hpp"

#include <dds/dds.h>
#include <dlfcn.h>
#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <memory>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/xml_text.hpp"

namespace sensornet::dds {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRemake = "make new files with `sensornet pki init DIR --force`";

struct BioFree {
  void operator()(BIO* b) const noexcept { BIO_free(b); }
};
struct X509Free {
  void operator()(X509* x) const noexcept { X509_free(x); }
};
struct KeyFree {
  void operator()(EVP_PKEY* k) const noexcept { EVP_PKEY_free(k); }
};
using Bio = std::unique_ptr<BIO, BioFree>;
using Certificate = std::unique_ptr<X509, X509Free>;
using PrivateKey = std::unique_ptr<EVP_PKEY, KeyFree>;

void requireFile(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    throw InputError(path.string(), "", "a file of the security folder (missing; " +
                                            std::string(kRemake) + ")");
  }
}

Bio openFile(const fs::path& path) {
  Bio bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) throw InputError(path.string(), "", "a readable file");
  return bio;
}

Certificate loadCertificate(const fs::path& path) {
  const Bio bio = openFile(path);
  Certificate cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) throw InputError(path.string(), "", "a PEM certificate");
  return cert;
}

std::string timeText(const ASN1_TIME* time) {
  const Bio bio(BIO_new(BIO_s_mem()));
  if (!bio || ASN1_TIME_print(bio.get(), time) != 1) return "?";
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<std::size_t>(size));
}

void checkValidNow(const X509* cert, const fs::path& path) {
  const ASN1_TIME* not_before = X509_get0_notBefore(cert);
  const ASN1_TIME* not_after = X509_get0_notAfter(cert);
  if (X509_cmp_current_time(not_before) >= 0) {
    throw InputError(path.string(), "certificate",
                     "a certificate valid now (it is valid only from " + timeText(not_before) +
                         ": is this host's clock right?)");
  }
  if (X509_cmp_current_time(not_after) <= 0) {
    throw InputError(path.string(), "certificate",
                     "a certificate valid now (it expired " + timeText(not_after) + "; " +
                         kRemake + ")");
  }
}

void checkSignedBy(X509* cert, X509* ca, const SecurityFiles& files) {
  EVP_PKEY* ca_key = X509_get0_pubkey(ca);
  if (ca_key == nullptr || X509_verify(cert, ca_key) != 1 ||
      X509_check_issued(ca, cert) != X509_V_OK) {
    throw InputError(files.certificate.string(), "certificate",
                     "a certificate signed by the CA " + files.ca.string() +
                         " (it is not signed by that CA: made by another `pki init`?)");
  }
}

void checkKeyMatches(X509* cert, const SecurityFiles& files) {
  const Bio bio = openFile(files.private_key);
  const PrivateKey key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
  if (!key) throw InputError(files.private_key.string(), "", "an unencrypted PEM private key");
  if (X509_check_private_key(cert, key.get()) != 1) {
    throw InputError(files.private_key.string(), "",
                     "the private key of " + files.certificate.string());
  }
}

// "file:/abs/path"; a comma would split Cyclone's list of configuration fragments.
std::string fileUri(const fs::path& path) {
  const std::string text = path.string();
  if (text.find(',') != std::string::npos) {
    throw InputError(text, "", "a path without ',' (Cyclone's configuration list splits on it)");
  }
  return "file:" + escapeXml(text);
}

std::string library(const std::string& name, const char* init, const char* finalize) {
  const fs::path dir = securityPluginDirectory();
  const std::string path = dir.empty() ? name : (dir / ("lib" + name + ".so")).string();
  return "<Library path=\"" + escapeXml(path) + "\" initFunction=\"" + init +
         "\" finalizeFunction=\"" + finalize + "\"/>";
}

std::string subjectOf(const fs::path& certificate) {
  try {
    const Certificate cert = loadCertificate(certificate);
    char text[512];
    X509_NAME_oneline(X509_get_subject_name(cert.get()), text, sizeof text);
    return text;
  } catch (const InputError&) {
    return "?";
  }
}

}  // namespace

std::string_view securityRoleName(SecurityRole role) noexcept {
  switch (role) {
    case SecurityRole::Coordinator: return "coordinator";
    case SecurityRole::FusionCenter: return "fusion_center";
    case SecurityRole::Sensor: return "sensor";
    case SecurityRole::Operator: return "operator";
    case SecurityRole::Launcher: return "launcher";
  }
  return "?";
}

SecurityFiles securityFilesOf(const fs::path& dir, SecurityRole role) {
  std::error_code error;
  const fs::path base = fs::absolute(dir, error).lexically_normal();
  const fs::path own = base / securityRoleName(role);
  return {base / "ca.pem", base / "governance.p7s", own / "identity.pem", own / "key.pem",
          own / "permissions.p7s"};
}

void checkSecurityFiles(const SecurityFiles& files) {
  for (const fs::path& path :
       {files.ca, files.governance, files.certificate, files.private_key, files.permissions}) {
    requireFile(path);
  }
  const Certificate ca = loadCertificate(files.ca);
  checkValidNow(ca.get(), files.ca);
  const Certificate cert = loadCertificate(files.certificate);
  checkSignedBy(cert.get(), ca.get(), files);
  checkValidNow(cert.get(), files.certificate);
  checkKeyMatches(cert.get(), files);
}

void checkSecurityFolder(const fs::path& dir) {
  for (const SecurityRole role : kSecurityRoles) checkSecurityFiles(securityFilesOf(dir, role));
}

std::string securityConfigXml(const SecurityFiles& files) {
  const std::string ca = fileUri(files.ca);
  return "<CycloneDDS><Domain id=\"any\"><Security><Authentication>" +
         library("dds_security_auth", "init_authentication", "finalize_authentication") +
         "<IdentityCertificate>" + fileUri(files.certificate) + "</IdentityCertificate>" +
         "<IdentityCA>" + ca + "</IdentityCA><PrivateKey>" + fileUri(files.private_key) +
         "</PrivateKey></Authentication><AccessControl>" +
         library("dds_security_ac", "init_access_control", "finalize_access_control") +
         "<PermissionsCA>" + ca + "</PermissionsCA><Governance>" + fileUri(files.governance) +
         "</Governance><Permissions>" + fileUri(files.permissions) +
         "</Permissions></AccessControl><Cryptographic>" +
         library("dds_security_crypto", "init_crypto", "finalize_crypto") +
         "</Cryptographic></Security></Domain></CycloneDDS>";
}

fs::path securityPluginDirectory() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &info) == 0 ||
      info.dli_fname == nullptr) {
    return {};
  }
  const fs::path ddsc_dir = fs::path(info.dli_fname).parent_path();
  std::error_code error;
  for (const fs::path& dir : {ddsc_dir, ddsc_dir / "libddsc0debian"}) {
    if (fs::is_regular_file(dir / "libdds_security_auth.so", error)) return dir;
  }
  return {};
}

std::string securityFailureHint(const SecurityFiles& files) {
  return "a participant Cyclone's security plugins accept: they refused " +
         files.certificate.string() + " (subject " + subjectOf(files.certificate) +
         ") with the permissions " + files.permissions.string() + " and the governance " +
         files.governance.string() +
         " (signed by another CA, or permissions for another subject or expired?); " + kRemake;
}

}  // namespace sensornet::dds
