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
//   DIR/<identity>/               what one process of that identity receives, and nothing else:
//     identity.pem                its certificate (CN=<identity>), signed by the CA
//     key.pem                     its private key
//     permissions.p7s             what it may publish and subscribe, signed by the CA
//     ca.pem, governance.p7s      copies of the CA certificate and the governance
//
// An identity is a role (coordinator, fusion_center, operator, launcher) or, for a sensor
// process, the block of sensors it speaks for: sensor-<ids> ("sensor-3", "sensor-0-4"), whose
// permissions allow it to publish in that block's partition only (emulator/run_partitions.hpp).
// `--security` takes DIR (a process then presents DIR/<identity>) or that folder itself.
//
//   const SecurityFiles files = securityFilesOf("run-pki", {SecurityRole::Sensor, "0-4"});
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
#include <utility>
#include <vector>

namespace sensornet::dds {

enum class SecurityRole { Coordinator, FusionCenter, Sensor, Operator, Launcher };

inline constexpr std::array<SecurityRole, 5> kSecurityRoles = {
    SecurityRole::Coordinator, SecurityRole::FusionCenter, SecurityRole::Sensor,
    SecurityRole::Operator, SecurityRole::Launcher};

// "coordinator", "fusion_center", "sensor", "operator", "launcher": the role's folder in DIR.
// (Inline, as SecurityIdentity::name: the launcher's policy documents use them without DDS.)
[[nodiscard]] constexpr std::string_view securityRoleName(SecurityRole role) noexcept {
  switch (role) {
    case SecurityRole::Coordinator: return "coordinator";
    case SecurityRole::FusionCenter: return "fusion_center";
    case SecurityRole::Sensor: return "sensor";
    case SecurityRole::Operator: return "operator";
    case SecurityRole::Launcher: return "launcher";
  }
  return "?";
}

// Who a process is in a secured run: its role and, for a sensor process, the sensors it speaks
// for, as formatSensorIds writes them ("0-4").
struct SecurityIdentity {
  SecurityIdentity(SecurityRole r = SecurityRole::Operator, std::string s = {})  // NOLINT: a role is an identity
      : role(r), sensors(std::move(s)) {}
  SecurityRole role;
  std::string sensors;
  // The folder name in DIR and the certificate's common name: "coordinator", "sensor-0-4".
  [[nodiscard]] std::string name() const {
    const std::string role_name(securityRoleName(role));
    return role == SecurityRole::Sensor && !sensors.empty() ? role_name + "-" + sensors
                                                            : role_name;
  }
};

struct SecurityFiles {
  std::filesystem::path ca;
  std::filesystem::path governance;
  std::filesystem::path certificate;
  std::filesystem::path private_key;
  std::filesystem::path permissions;
};

// The folder that holds what a process of `identity` presents: DIR/<identity> when `dir` is the
// folder `pki init` made, else `dir` itself (an identity's folder handed over alone).
[[nodiscard]] std::filesystem::path roleFolderOf(const std::filesystem::path& dir,
                                                 const SecurityIdentity& identity);
// The files of `identity` in `dir` (absolute paths; only the folders' layout is looked at): all
// in its folder, the CA certificate and governance from DIR when its folder lacks them.
[[nodiscard]] SecurityFiles securityFilesOf(const std::filesystem::path& dir,
                                            const SecurityIdentity& identity);

// Throws InputError naming the first file that is missing or unreadable, a certificate (CA or
// identity) that is expired or not yet valid, an identity not signed by the CA, a private key
// that does not belong to the certificate, a governance or permissions document whose S/MIME
// signature the CA did not make (one byte changed is enough), or permissions for another subject
// than the certificate's.
void checkSecurityFiles(const SecurityFiles& files);
// checkSecurityFiles for every role in `dir` and every sensor block in `sensor_blocks` (the
// identity of each sensor process a launch starts), and checkNoForeignSecrets for each folder:
// what the launcher does before it starts anything. A missing sensor identity is named with
// `make_sensor_identities`, the command that makes them.
void checkSecurityFolder(const std::filesystem::path& dir,
                         const std::vector<std::string>& sensor_blocks,
                         const std::string& make_sensor_identities);
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
