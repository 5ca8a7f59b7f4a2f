#include "sensornet/dds/domain.hpp"

#include <charconv>
#include <cstdint>

#include "sensornet/core/digest.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {
namespace detail {
// Defined in the source generated from config/cyclonedds-loopback.xml (src/dds/CMakeLists.txt).
extern const char* const kLoopbackConfigXml;
}  // namespace detail

namespace {

constexpr std::size_t kMaxRunIdLength = 64;

bool isRunIdCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-';
}

void validateDomainConfig(const DomainConfig& config) {
  if (config.domain_id > kMaxDomainId) {
    throw InputError("domain config", "domain_id",
                     "an integer in [0, " + std::to_string(kMaxDomainId) + "] (got " +
                         std::to_string(config.domain_id) + ")");
  }
  if (config.partition.find_first_of("*?") != std::string::npos) {
    throw InputError("domain config", "partition", "a name without the wildcards '*' and '?'");
  }
}

}  // namespace

DomainConfig DomainConfig::loopback(dds_domainid_t domain_id, std::string partition,
                                    DiscoveryRole role) {
  std::string xml = loopbackConfigXml();
  xml += "," + (role == DiscoveryRole::Leaf ? leafConfigXml() : hubConfigXml());
  return DomainConfig{domain_id, std::move(partition), std::move(xml), {}, {}};
}

DomainConfig DomainConfig::forRun(std::string_view run_id, DiscoveryRole role) {
  validateRunId(run_id, "domain config");
  return loopback(domainIdForRun(run_id), "sensornet/" + std::string(run_id), role);
}

void validateRunId(std::string_view run_id, const std::string& source) {
  bool ok = !run_id.empty() && run_id.size() <= kMaxRunIdLength;
  for (char c : run_id) ok = ok && isRunIdCharacter(c);
  if (!ok) {
    throw InputError(
        source, "run_id",
        "1 to 64 letters, digits, '.', '_' or '-' (got '" + std::string(run_id) + "')");
  }
}

dds_domainid_t domainIdForRun(std::string_view run_id) {
  return static_cast<dds_domainid_t>(1 + fnv1a64(run_id) % kMaxDomainId);
}

dds_domainid_t parseDomainId(std::string_view text, const std::string& source) {
  unsigned long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || value > kMaxDomainId) {
    throw InputError(source, "domain id",
                     "an integer in [0, " + std::to_string(kMaxDomainId) + "] (got '" +
                         std::string(text) + "')");
  }
  return static_cast<dds_domainid_t>(value);
}

const std::string& leafConfigXml() {
  static const std::string xml =
      R"(<CycloneDDS><Domain Id="any"><Discovery><ParticipantIndex>none</ParticipantIndex>)"
      R"(</Discovery></Domain></CycloneDDS>)";
  return xml;
}

const std::string& hubConfigXml() {
  static const std::string xml =
      R"(<CycloneDDS><Domain Id="any"><Internal><HeartbeatInterval max="1 s">1 s</HeartbeatInterval>)"
      R"(</Internal></Domain></CycloneDDS>)";
  return xml;
}

const std::string& writeBatchConfigXml() {
  static const std::string xml =
      R"(<CycloneDDS><Domain Id="any"><Internal><WriteBatch>true</WriteBatch></Internal>)"
      R"(</Domain></CycloneDDS>)";
  return xml;
}

const std::string& loopbackConfigXml() {
  static const std::string xml(detail::kLoopbackConfigXml);
  return xml;
}

Domain::Domain(DomainConfig config, const CApi& api)
    : Entity(api,
             [&] {
               validateDomainConfig(config);
               std::string xml = config.cyclone_config;
               if (config.write_batching) xml += "," + writeBatchConfigXml();
               if (!config.security_xml.empty()) xml += "," + config.security_xml;
               return check(api.create_domain(config.domain_id, xml.c_str()),
                            "dds_create_domain");
             }()),
      config_(std::move(config)) {}

}  // namespace sensornet::dds
