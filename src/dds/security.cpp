#include "sensornet/dds/security.hpp"

#include <dds/dds.h>
#include <dlfcn.h>
#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>
#include <openssl/x509v3.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <vector>

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
struct Pkcs7Free {
  void operator()(PKCS7* p) const noexcept { PKCS7_free(p); }
};
struct StoreFree {
  void operator()(X509_STORE* s) const noexcept { X509_STORE_free(s); }
};
using Bio = std::unique_ptr<BIO, BioFree>;
using Certificate = std::unique_ptr<X509, X509Free>;
using PrivateKey = std::unique_ptr<EVP_PKEY, KeyFree>;
using Pkcs7 = std::unique_ptr<PKCS7, Pkcs7Free>;
using Store = std::unique_ptr<X509_STORE, StoreFree>;

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

// The content of an S/MIME document if its signature verifies against the CA (the signer's
// certificate chains to it and the content is unchanged); InputError naming the file otherwise.
std::string verifiedContent(const fs::path& document, X509* ca) {
  const Bio in = openFile(document);
  BIO* detached = nullptr;
  const Pkcs7 p7(SMIME_read_PKCS7(in.get(), &detached));
  const Bio content(detached);
  if (!p7) throw InputError(document.string(), "", "an S/MIME document signed by the CA");
  const Store store(X509_STORE_new());
  if (!store || X509_STORE_add_cert(store.get(), ca) != 1) {
    throw std::runtime_error("cannot set up a certificate store to check " + document.string());
  }
  X509_STORE_set_purpose(store.get(), X509_PURPOSE_ANY);
  const Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store.get(), content.get(), out.get(), PKCS7_TEXT) != 1) {
    throw InputError(document.string(), "signature",
                     "a document signed by the CA (its S/MIME signature does not verify: changed "
                     "after signing, or signed by another CA; " +
                         std::string(kRemake) + ")");
  }
  char* data = nullptr;
  const long size = BIO_get_mem_data(out.get(), &data);
  return std::string(data, static_cast<std::size_t>(std::max(size, 0L)));
}

// The attributes of a distinguished name as "key=value" strings, in any order: "CN=sensor,
// O=sensornet" and the certificate's "/O=sensornet/CN=sensor" give the same set.
std::set<std::string> nameParts(const std::string& text, char separator) {
  std::set<std::string> parts;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, separator)) {
    part.erase(0, part.find_first_not_of(' '));
    if (!part.empty()) parts.insert(part);
  }
  return parts;
}

std::string subjectLine(X509* cert) {
  char text[512];
  X509_NAME_oneline(X509_get_subject_name(cert), text, sizeof text);
  return text;
}

// The permissions grant the subject of the certificate (Cyclone refuses the participant
// otherwise, with a message that does not name the file).
void checkPermissionsSubject(const std::string& permissions, X509* cert,
                             const SecurityFiles& files) {
  const std::string open = "<subject_name>", close = "</subject_name>";
  const std::size_t from = permissions.find(open);
  const std::size_t to = permissions.find(close, from);
  if (from == std::string::npos || to == std::string::npos) {
    throw InputError(files.permissions.string(), "subject_name", "a permissions document");
  }
  const std::string granted = permissions.substr(from + open.size(), to - from - open.size());
  const std::string subject = subjectLine(cert);
  if (nameParts(granted, ',') != nameParts(subject, '/')) {
    throw InputError(files.permissions.string(), "subject_name",
                     "permissions for " + files.certificate.string() + " (subject " + subject +
                         "), not for '" + granted + "'");
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
    return subjectLine(cert.get());
  } catch (const InputError&) {
    return "?";
  }
}

}  // namespace

fs::path roleFolderOf(const fs::path& dir, const SecurityIdentity& identity) {
  std::error_code error;
  const fs::path base = fs::absolute(dir, error).lexically_normal();
  const fs::path own = base / identity.name();
  return fs::is_directory(own, error) ? own : base;
}

SecurityFiles securityFilesOf(const fs::path& dir, const SecurityIdentity& identity) {
  std::error_code error;
  const fs::path base = fs::absolute(dir, error).lexically_normal();
  const fs::path own = roleFolderOf(base, identity);
  // A folder from before the CA's files were copied into each role's folder keeps them in DIR.
  const auto shared = [&](const char* name) {
    return fs::exists(own / name, error) || own == base ? own / name : base / name;
  };
  return {shared("ca.pem"), shared("governance.p7s"), own / "identity.pem", own / "key.pem",
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
  (void)verifiedContent(files.governance, ca.get());
  checkPermissionsSubject(verifiedContent(files.permissions, ca.get()), cert.get(), files);
}

void checkSecurityFolder(const fs::path& dir, const std::vector<std::string>& sensor_blocks,
                         const std::string& make_sensor_identities) {
  std::vector<SecurityIdentity> identities;
  for (const SecurityRole role : kSecurityRoles) {
    if (role != SecurityRole::Sensor) identities.emplace_back(role);
  }
  for (const std::string& block : sensor_blocks) identities.emplace_back(SecurityRole::Sensor, block);
  std::error_code error;
  const fs::path base = fs::absolute(dir, error).lexically_normal();
  for (const SecurityIdentity& identity : identities) {
    const fs::path own = roleFolderOf(base, identity);
    if (own == base) {
      throw InputError((base / identity.name()).string(), "",
                       "the folder of the identity " + identity.name() +
                           (identity.role == SecurityRole::Sensor
                                ? " (the sensor process for sensors " + identity.sensors +
                                      "): make the identities of this launch's sensor "
                                      "processes with `" + make_sensor_identities + "`"
                                : std::string(": made by `sensornet pki init`")));
    }
    checkSecurityFiles(securityFilesOf(base, identity));
    checkNoForeignSecrets(own);
  }
}

void checkNoForeignSecrets(const fs::path& role_folder) {
  std::error_code error;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(role_folder, error)) {
    const fs::path& path = entry.path();
    if (entry.is_directory(error)) {
      throw InputError(path.string(), "",
                       "no folder inside a role's folder (a process receives its own files only)");
    }
    if (path.filename() == "key.pem" && path.parent_path() == role_folder) continue;
    std::ifstream in(path);
    std::string line;
    bool key = path.filename() == "ca.key";
    while (!key && std::getline(in, line)) key = line.find("PRIVATE KEY-----") != std::string::npos;
    if (key) {
      throw InputError(path.string(), "",
                       "no private key but the role's own key.pem in the folder a process "
                       "receives (the CA's key stays with `pki init`, see --ca-dir)");
    }
  }
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
