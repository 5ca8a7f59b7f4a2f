#pragma once
// DDS Security for a run (issue 12, part 3): the files one process presents, checked before
// Cyclone sees them, and the Cyclone <Security> fragment that turns on the authentication,
// access-control and crypto plugins with them. The files are those `sensornet pki init DIR`
// makes (launcher/pki_command.hpp):
//
//   DIR/ca/ca.key, DIR/ca/ca.pem  the CA: its private key never goes to a run's processes
//                                 (or elsewhere, with `pki init --ca-dir`)
//   DIR/ca.pem                    identity CA, also the permissions CA (its certificate)
//   DIR/governance.p7s            governance, signed by the CA (S/MIME)
//   DIR/<role>/                   what one process of that role receives, and nothing else:
//     identity.pem                the role's certificate, signed by the CA
//     key.pem                     its private key
//     permissions.p7s             what the role may publish and subscribe, signed by the CA
//     ca.pem, governance.p7s      copies of the CA certificate and the governance
//
// `--security` takes DIR (a process then presents DIR/<role>) or a role's folder itself.
//
//   const SecurityFiles files = securityFilesOf("run-pki", SecurityRole::Sensor);
//   checkSecurityFiles(files);  // InputError naming the file: missing, expired, another CA's
//   config.cyclone_config += "," + securityConfigXml(files);
//
// A process whose files pass these checks may still be refused by Cyclone (a permissions
// document for another subject, say): dds_create_participant then fails, and the caller turns
// that into one line with securityFailureHint().

#include <array>
#include <filesystem>
#include <string>
#include <string_view>

namespace sensornet::dds {

enum class SecurityRole { Coordinator, FusionCenter, Sensor, Operator, Launcher };

inline constexpr std::array<SecurityRole, 5> kSecurityRoles = {
    SecurityRole::Coordinator, SecurityRole::FusionCenter, SecurityRole::Sensor,
    SecurityRole::Operator, SecurityRole::Launcher};

// "coordinator", "fusion_center", "sensor", "operator", "launcher": the role's folder in DIR.
[[nodiscard]] std::string_view securityRoleName(SecurityRole role) noexcept;

struct SecurityFiles {
  std::filesystem::path ca;
  std::filesystem::path governance;
  std::filesystem::path certificate;
  std::filesystem::path private_key;
  std::filesystem::path permissions;
};

// The folder that holds what a process of `role` presents: DIR/<role> when `dir` is the folder
// `pki init` made, else `dir` itself (a role's folder handed over alone).
[[nodiscard]] std::filesystem::path roleFolderOf(const std::filesystem::path& dir,
                                                 SecurityRole role);
// The files of `role` in `dir` (absolute paths; only the folders' layout is looked at): all in
// its role folder, the CA certificate and governance from DIR when the role folder lacks them.
[[nodiscard]] SecurityFiles securityFilesOf(const std::filesystem::path& dir, SecurityRole role);

// Throws InputError naming the first file that is missing or unreadable, a certificate (CA or
// identity) that is expired or not yet valid, an identity not signed by the CA, a private key
// that does not belong to the certificate, a governance or permissions document whose S/MIME
// signature the CA did not make (one byte changed is enough), or permissions for another subject
// than the certificate's.
void checkSecurityFiles(const SecurityFiles& files);
// checkSecurityFiles for every role in `dir`, and checkNoForeignSecrets for each role folder:
// what the launcher does before it starts anything.
void checkSecurityFolder(const std::filesystem::path& dir);
// Throws InputError naming a file in the folder a process of `role` receives that it must not
// have: a CA private key (ca.key, or any PEM private key but its own key.pem) or another role's
// folder.
void checkNoForeignSecrets(const std::filesystem::path& role_folder);

// <CycloneDDS><Domain id="any"><Security>...</Security></Domain></CycloneDDS>, to be appended to
// the domain's configuration (Cyclone merges comma-separated fragments).
[[nodiscard]] std::string securityConfigXml(const SecurityFiles& files);

// The folder that holds Cyclone's security plugins (libdds_security_auth.so ...): beside libddsc
// or in its libddsc0debian/ subfolder (Debian); empty if neither has them (then Cyclone searches
// the loader's path).
[[nodiscard]] std::filesystem::path securityPluginDirectory();

// What most likely made Cyclone refuse a secured participant, for a one-line error.
[[nodiscard]] std::string securityFailureHint(const SecurityFiles& files);

}  // namespace sensornet::dds
