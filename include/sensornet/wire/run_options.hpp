#pragma once
// How every emulator process (coordinator serve, sensor_agent, fusion_center serve, the
// launcher) names the run it belongs to and reaches its DDS domain. The same three flags
// everywhere:
//   --run-id ID           the run: partition "sensornet/ID", domain id hashed from ID
//   --domain-id D         override the domain id (0..230)
//   --cyclone-config X    Cyclone configuration (XML text or file:// URI) instead of the
//                         shipped loopback-only one; also from SENSORNET_CYCLONE_CONFIG.
//
//   RunOptions run;
//   addRunOptions(*cmd, run);                  // while building the CLI
//   dds::Domain domain(run.domainConfig());    // after parsing
//
// Without --cyclone-config (and without the environment variable) every process uses the
// loopback-only configuration compiled into sensornet_dds: bound to lo, unicast discovery to
// 127.0.0.1, no multicast. Running across hosts takes an explicit configuration (docker/).

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/security.hpp"
#include "sensornet/io/forwarded_options.hpp"

namespace sensornet::wire {

// Limits of the numeric options (--time-scale, --episodes, wall-clock durations): declared with
// the options the launcher forwards (io/forwarded_options.hpp).
using sensornet::kMaxEpisodes;
using sensornet::kMaxTimeScale;
using sensornet::kMaxWallSeconds;
using sensornet::kMinEpisodes;
using sensornet::kMinTimeScale;

// The environment variable read when --cyclone-config is not given.
inline constexpr const char* kCycloneConfigVariable = "SENSORNET_CYCLONE_CONFIG";

struct RunOptions {
  std::string run_id;
  std::optional<int> domain_id;
  std::string cyclone_config;  // empty: SENSORNET_CYCLONE_CONFIG, else the loopback config
  // --security DIR (`sensornet pki init`): DDS Security with this process's role's files, which
  // are checked (InputError naming a missing, expired or foreign file) by domainConfig().
  std::string security_dir;
  // Set by each program: its role, and for a sensor agent the sensors it speaks for.
  dds::SecurityIdentity security_identity = dds::SecurityRole::Operator;

  // Throws InputError for a bad run id or domain id. A cyclone_config that names an existing
  // file path (not a URI, not XML) is turned into a file:// URI.
  // The shipped loopback configuration for `role` (domain.hpp), unless --cyclone-config or
  // $SENSORNET_CYCLONE_CONFIG names another, which is used as given for every role.
  [[nodiscard]] dds::DomainConfig domainConfig(
      dds::DiscoveryRole role = dds::DiscoveryRole::Hub) const;
  // The Cyclone configuration domainConfig() uses: --cyclone-config, else the environment
  // variable; empty for the loopback configuration (only this host is heard).
  [[nodiscard]] std::string chosenCycloneConfig() const;
  // The flags another command on this host needs to reach the run (`sensornet status`,
  // `replan`, `watch`, `record`): --run-id, then --domain-id, --cyclone-config (`cyclone_config`
  // when given, else the one set here) and --security where they differ from the defaults.
  [[nodiscard]] std::vector<std::string> reachFlags(const std::string& cyclone_config = "") const;
};

// Adds --run-id (required unless `run_id_required` is false), --domain-id, --cyclone-config and
// --security.
void addRunOptions(CLI::App& app, RunOptions& options, bool run_id_required = true);

}  // namespace sensornet::wire
