#pragma once
// The documents of a secured run that `sensornet pki init` signs (DDS Security, issue 12 part
// 3), as pure functions of their inputs: the governance (who may join which domains, what is
// protected) and each identity's permissions (what it may publish and subscribe, in which
// partitions); which identities a folder gets; which files `pki init --force` may replace.
// launcher/pki_command.cpp runs openssl with them.
//
//   const std::vector<dds::SecurityIdentity> ids = securityIdentities({{0, 1}, {2}});
//   // coordinator, fusion_center, operator, launcher, sensor-0-1, sensor-2
//   writeText(dir / "governance.xml", governanceXml());
//   writeText(own / "permissions.xml",
//             permissionsXml(ids[4], {"2026-12-04T10:00:00", "2027-12-05T10:00:00"}));
//
// A sensor process may publish only in its own block's partition (sensornet/*/sensors/<ids>),
// the launcher and an operator each only in their own Command partition, so that the
// coordinator knows who sent a command (emulator/run_partitions.hpp); the run's id is not known
// when the documents are made: "*" stands for it.

#include <string>
#include <vector>

#include "sensornet/dds/security.hpp"  // SecurityIdentity: header-only names, no DDS

namespace sensornet::launcher {

// Who writes and who reads which topic (each program's writers and readers, "Scenario" for
// sensornet/Scenario), and in which partition it may publish; it subscribes in "sensornet/*".
struct TopicRights {
  std::vector<std::string> publish;
  std::vector<std::string> subscribe;
  std::string publish_partition = "sensornet/*";
};

[[nodiscard]] TopicRights rightsOf(const dds::SecurityIdentity& identity);

// The governance document: domains 0..230, only authenticated participants, discovery and
// liveliness encrypted, every topic read- and write-access controlled, its payload encrypted and
// its submessages signed.
[[nodiscard]] std::string governanceXml();

// When a permissions document is valid, as DDS Security writes it: "2026-11-30T21:00:00" (UTC).
struct Validity {
  std::string not_before;
  std::string not_after;
};

// The permissions of `identity` (subject CN=<identity>,O=sensornet): rightsOf, allowed in
// domains 0..230 during `validity`, everything else denied.
[[nodiscard]] std::string permissionsXml(const dds::SecurityIdentity& identity,
                                         const Validity& validity);

// The identities `pki init` makes: every role but the sensor role, then one sensor process
// identity per distinct block of `sensor_blocks`, in order.
[[nodiscard]] std::vector<dds::SecurityIdentity> securityIdentities(
    const std::vector<std::vector<int>>& sensor_blocks);

// What `pki init` makes, by folder: only these names are replaced by --force. In DIR (Root):
// the CA's certificate, the governance, the CA's folder, a folder per role and one per sensor
// process ("sensor-<ids>"); in an identity's folder (Identity): its certificate, key,
// permissions and copies of the CA certificate and governance; in the CA's folder: its key and
// certificate.
enum class PkiFolder { Root, Identity, Ca };
[[nodiscard]] bool madeByPkiInit(PkiFolder folder, const std::string& name);

}  // namespace sensornet::launcher
