#pragma once
// Run isolation and the DDS domain of a process. A DomainConfig is a value chosen by the caller:
// the domain id and the partition that keep one emulation run apart from every other run on the
// host, and the Cyclone configuration to create the domain with. A Domain creates that domain
// explicitly (dds_create_domain) with the configuration, so nothing depends on CYCLONEDDS_URI
// and nothing ever runs with Cyclone's default, non-loopback configuration.
//
//   DomainConfig config = DomainConfig::forRun("run-42");  // loopback, domain id from the run id
//   Domain domain(config);
//   Participant participant(domain);                      // participant.hpp
//
// One Domain per domain id per process: Cyclone refuses to create a domain twice (DdsError with
// "Precondition not met"); every participant of the process shares it. The domain must outlive
// its participants.

#include <dds/dds.h>

#include <string>
#include <string_view>

#include "sensornet/dds/c_api.hpp"
#include "sensornet/dds/entity.hpp"

namespace sensornet::dds {

// With the shipped configuration (MaxAutoParticipantIndex 31) Cyclone's default port mapping
// 7400 + 250 d + 10 + 2 i stays below 65536 for every domain id d <= 230.
inline constexpr dds_domainid_t kMaxDomainId = 230;

// How a process takes part in discovery on the shipped loopback configuration, so that its cost
// grows with the number of processes, not its square (config/cyclonedds-loopback.xml):
// - Hub: the coordinator, the fusion center, the launcher and the tools. A hub takes a
//   participant index (one of 0..31, so its ports are known) and probes those ports, so hubs
//   find each other.
// - Leaf: a sensor agent. It takes no index (arbitrary ports, nobody can probe it) and probes
//   the hubs' ports; a hub answers the leaf's announcement directly. Leaves never discover one
//   another, which they never talk to anyway.
// A hub also asks for acknowledgements once a second instead of every 100 ms (hubConfigXml):
// while leaves join, every hub writer with data some of them still lack heartbeats *all* its
// readers (Cyclone sends one heartbeat to every matched reader as soon as two are behind), and
// each leaf that joins restarts that at the fastest rate. At 100 ms, 200 sensor processes
// starting at once made 3x the packets and took twice as long (bench/README.md, "Start-up at
// scale"). Leaves keep 100 ms: their measurements are what must be repaired promptly.
enum class DiscoveryRole { Hub, Leaf };

struct DomainConfig {
  dds_domainid_t domain_id = 0;
  // Every writer and reader made through a Participant of this domain joins this partition
  // (unless its own QoS names one). Empty: the default partition.
  std::string partition;
  // Given verbatim to dds_create_domain: XML text and/or file URIs, comma-separated.
  std::string cyclone_config;
  // DDS Security (security.hpp): a <Security> fragment appended to cyclone_config when the
  // domain is created (kept apart so that cyclone_config can be handed to another process that
  // presents its own files), and why Cyclone most likely refused a participant, so that the
  // refusal is one line naming the files, not a bare return code.
  std::string security_xml;
  std::string security_hint;
  // Cyclone's write batching (Internal/WriteBatch) for this domain's writers. Each write still
  // goes out at once, except inside a Writer's burst (writer.hpp), whose writes share packets
  // and go out when the burst ends: fewer sendmsg calls for the writer and fewer datagrams for
  // the readers when a process has several samples ready at once.
  bool write_batching = false;

  // The shipped loopback configuration on `domain_id`, with `partition`, for `role`.
  [[nodiscard]] static DomainConfig loopback(dds_domainid_t domain_id, std::string partition,
                                             DiscoveryRole role = DiscoveryRole::Hub);
  // Loopback, on domainIdForRun(run_id), in partition "sensornet/<run_id>". Throws InputError
  // if run_id is not a run id (see validateRunId).
  [[nodiscard]] static DomainConfig forRun(std::string_view run_id,
                                           DiscoveryRole role = DiscoveryRole::Hub);
};

// Throws InputError(source, "run_id", ...) unless run_id is 1 to 64 characters from letters,
// digits, '.', '_' and '-' (it becomes part of a partition name and of file names).
void validateRunId(std::string_view run_id, const std::string& source);

// A domain id in [1, kMaxDomainId] from a hash of the run id, so that independent runs on one
// host most likely use different domains (different ports); the partition isolates them anyway.
[[nodiscard]] dds_domainid_t domainIdForRun(std::string_view run_id);

// Parses a domain id given as text (a command-line flag, an environment variable); throws
// InputError(source, "domain id", "an integer in [0, 230]") otherwise.
[[nodiscard]] dds_domainid_t parseDomainId(std::string_view text, const std::string& source);

// The text of config/cyclonedds-loopback.xml, compiled into the library.
[[nodiscard]] const std::string& loopbackConfigXml();
// What a leaf adds to a configuration (Cyclone reads a comma-separated list of XML fragments,
// the later ones overriding): participant index none.
[[nodiscard]] const std::string& leafConfigXml();
// What a hub adds: heartbeats once a second (see DiscoveryRole).
[[nodiscard]] const std::string& hubConfigXml();
// What DomainConfig::write_batching adds.
[[nodiscard]] const std::string& writeBatchConfigXml();

class Domain : public Entity {
 public:
  // Creates the domain; throws InputError for a domain id above kMaxDomainId or a partition with
  // wildcards, DdsError if Cyclone refuses (e.g. the domain exists already in this process).
  explicit Domain(DomainConfig config, const CApi& api = realCApi());

  [[nodiscard]] const DomainConfig& config() const noexcept { return config_; }

 private:
  DomainConfig config_;
};

}  // namespace sensornet::dds
