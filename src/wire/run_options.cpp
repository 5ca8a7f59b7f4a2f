#include "sensornet/wire/run_options.hpp"

#include <cstdlib>
#include <filesystem>

#include "sensornet/core/input_error.hpp"

namespace sensornet::wire {
namespace {

constexpr const char* kSource = "command line";

// XML text and URIs go to Cyclone verbatim; a plain path to an existing file becomes a URI.
std::string asCycloneConfig(const std::string& text) {
  if (text.empty() || text.front() == '<' || text.find("://") != std::string::npos) return text;
  std::error_code error;
  const std::filesystem::path path = std::filesystem::absolute(text, error);
  if (error || !std::filesystem::is_regular_file(path, error)) {
    throw InputError(kSource, "--cyclone-config",
                     "Cyclone XML text, a file:// URI or an existing file, got '" + text + "'");
  }
  return "file://" + path.string();
}

// Turns on DDS Security with the identity's files in `dir`, checked first.
void addSecurity(dds::DomainConfig& config, const std::string& dir,
                 const dds::SecurityIdentity& identity) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) {
    throw InputError("--security " + dir, "", "a folder made by `sensornet pki init`");
  }
  const dds::SecurityFiles files = dds::securityFilesOf(dir, identity);
  dds::checkSecurityFiles(files);
  config.security_xml = dds::securityConfigXml(files);
  config.security_hint = dds::securityFailureHint(files);
}

}  // namespace

std::string RunOptions::chosenCycloneConfig() const {
  if (!cyclone_config.empty()) return cyclone_config;
  const char* from_environment = std::getenv(kCycloneConfigVariable);
  return from_environment != nullptr ? from_environment : "";
}

std::vector<std::string> RunOptions::reachFlags(const std::string& config) const {
  std::vector<std::string> flags = {"--run-id", run_id};
  if (domain_id) flags.insert(flags.end(), {"--domain-id", std::to_string(*domain_id)});
  const std::string& chosen = config.empty() ? cyclone_config : config;
  if (!chosen.empty()) flags.insert(flags.end(), {"--cyclone-config", chosen});
  if (!security_dir.empty()) flags.insert(flags.end(), {"--security", security_dir});
  return flags;
}

dds::DomainConfig RunOptions::domainConfig(dds::DiscoveryRole role) const {
  dds::validateRunId(run_id, kSource);
  dds::DomainConfig config = dds::DomainConfig::forRun(run_id, role);
  if (domain_id) {
    config.domain_id = dds::parseDomainId(std::to_string(*domain_id), "--domain-id");
  }
  if (const std::string chosen = chosenCycloneConfig(); !chosen.empty()) {
    config.cyclone_config = asCycloneConfig(chosen);
  }
  if (!security_dir.empty()) addSecurity(config, security_dir, security_identity);
  return config;
}

void addRunOptions(CLI::App& app, RunOptions& options, bool run_id_required) {
  auto* run = app.add_option("--run-id", options.run_id,
                             "the emulation run (letters, digits, '.', '_', '-'): its DDS "
                             "partition is sensornet/ID and its domain id a hash of ID");
  if (run_id_required) run->required();
  app.add_option("--domain-id", options.domain_id,
                 "DDS domain id (0..230) instead of the one hashed from the run id");
  app.add_option("--cyclone-config", options.cyclone_config,
                 "Cyclone DDS configuration (XML text, file:// URI or file path) instead of the "
                 "shipped loopback-only one; default: $SENSORNET_CYCLONE_CONFIG if set");
  app.add_option("--security", options.security_dir,
                 "DDS Security with the files `sensornet pki init DIR` made (this program's "
                 "role's identity and permissions): authenticated, access-controlled, encrypted");
}

}  // namespace sensornet::wire
