#include "scenario_network.hpp"

#include <cstdint>
#include <set>
#include <sstream>
#include <string>

#include "sensornet/core/network.hpp"

namespace sensornet {
namespace {

constexpr double kMaxEpisodeNumber = 4294967295.0;  // episodes are uint32 on the wire

std::string shown(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// A probability of the link (loss, duplicate): a number in [0, 1).
double probability(const YamlReader& in, const YAML::Node& node, const std::string& field) {
  const double p = in.number(node, field);
  if (p < 0.0 || p >= 1.0) in.fail(node, field, "a probability in [0, 1), got " + shown(p));
  return p;
}

// Emulated seconds of delay: in [0, T] (or (0, T] for a jitter mean).
double delaySeconds(const YamlReader& in, const YAML::Node& node, const std::string& field,
                    double horizon_s, bool positive) {
  const double seconds = in.number(node, field);
  const bool low_ok = positive ? seconds > 0.0 : seconds >= 0.0;
  if (!low_ok || seconds > horizon_s) {
    in.fail(node, field,
            std::string("seconds in ") + (positive ? "(0, " : "[0, ") + shown(horizon_s) +
                "] (at most the horizon), got " + shown(seconds));
  }
  return seconds;
}

Jitter jitterOf(const YamlReader& in, const YAML::Node& node, const std::string& field) {
  const std::string name = node.IsScalar() ? node.Scalar() : "";
  if (name == "none") return Jitter::None;
  if (name == "exponential") return Jitter::Exponential;
  if (name == "lognormal") return Jitter::Lognormal;
  in.fail(node, field, "one of none, exponential, lognormal, got '" + shortened(name) + "'");
}

// A link as read so far: the default, then one sensor's override fields on top of it.
struct LinkDraft {
  LinkSpec link;
  bool has_mean = false;
  bool has_sigma = false;
};

void readDelay(const YamlReader& in, const YAML::Node& delay, const std::string& field,
               double horizon_s, LinkDraft& draft) {
  in.rejectUnknownKeys(delay, field, {"fixed", "jitter", "mean", "sigma"});
  if (delay["fixed"]) {
    draft.link.delay_fixed_s =
        delaySeconds(in, delay["fixed"], field + ".fixed", horizon_s, /*positive=*/false);
  }
  if (delay["jitter"]) draft.link.jitter = jitterOf(in, delay["jitter"], field + ".jitter");
  if (delay["mean"]) {
    draft.link.jitter_mean_s =
        delaySeconds(in, delay["mean"], field + ".mean", horizon_s, /*positive=*/true);
    draft.has_mean = true;
    if (draft.link.jitter == Jitter::None) {
      in.fail(delay["mean"], field + ".mean",
              "no mean with jitter: none (give jitter: exponential or lognormal)");
    }
  }
  if (delay["sigma"]) {
    const double sigma = in.number(delay["sigma"], field + ".sigma");
    if (!(sigma > 0.0 && sigma <= kMaxLognormalSigma)) {
      in.fail(delay["sigma"], field + ".sigma",
              "a number in (0, " + shown(kMaxLognormalSigma) + "], got " + shown(sigma));
    }
    draft.link.jitter_sigma = sigma;
    draft.has_sigma = true;
    if (draft.link.jitter != Jitter::Lognormal) {
      in.fail(delay["sigma"], field + ".sigma",
              std::string("no sigma with jitter: ") +
                  (draft.link.jitter == Jitter::None ? "none" : "exponential") +
                  " (sigma is the spread of jitter: lognormal)");
    }
  }
}

// Applies the fields of `node` (a link mapping) to `draft`.
void readLinkFields(const YamlReader& in, const YAML::Node& node, const std::string& field,
                    double horizon_s, LinkDraft& draft) {
  in.rejectUnknownKeys(node, field, {"loss", "delay", "duplicate"});
  if (node["loss"]) draft.link.loss = probability(in, node["loss"], field + ".loss");
  if (node["duplicate"]) {
    draft.link.duplicate = probability(in, node["duplicate"], field + ".duplicate");
  }
  if (node["delay"]) readDelay(in, node["delay"], field + ".delay", horizon_s, draft);
}

// The link a draft resolves to: a jitter's mean is required, a lognormal's sigma defaults to
// 0.5, and the parameters a jitter does not use are zero.
LinkSpec finished(const YamlReader& in, const YAML::Node& node, const std::string& field,
                  LinkDraft draft) {
  LinkSpec& link = draft.link;
  if (link.jitter != Jitter::None && !draft.has_mean) {
    in.fail(node, field + ".delay.mean",
            "a value: the mean jitter in seconds (required for jitter: exponential and lognormal)");
  }
  if (link.jitter == Jitter::Lognormal && !draft.has_sigma) link.jitter_sigma = 0.5;
  if (link.jitter != Jitter::Lognormal) link.jitter_sigma = 0.0;
  if (link.jitter == Jitter::None) link.jitter_mean_s = 0.0;
  return link;
}

int sensorIndex(const YamlReader& in, const YAML::Node& node, const std::string& field,
                int sensors) {
  const long index = in.integer(node, field);
  if (index < 0 || index >= sensors) {
    in.fail(node, field,
            "a sensor index from 0 to " + std::to_string(sensors - 1) + ", got " +
                std::to_string(index));
  }
  return static_cast<int>(index);
}

std::uint32_t episodeNumber(const YamlReader& in, const YAML::Node& node,
                            const std::string& field) {
  const long episode = in.integer(node, field);
  if (episode < 0 || static_cast<double>(episode) > kMaxEpisodeNumber) {
    in.fail(node, field, "an episode number from 0 to 4294967295, got " + std::to_string(episode));
  }
  return static_cast<std::uint32_t>(episode);
}

void readLinks(const YamlReader& in, const YAML::Node& network, Scenario& s, NetworkSpec& spec) {
  LinkDraft base;
  const YAML::Node defaults = network["default"];
  if (defaults) {
    readLinkFields(in, defaults, "network.default", s.horizon_s, base);
    (void)finished(in, defaults, "network.default", base);
  }
  spec.links.assign(s.sensors.size(), finished(in, network, "network.default", base));
  const YAML::Node overrides = network["sensors"];
  if (!overrides) return;
  if (!overrides.IsMap()) {
    in.fail(overrides, "network.sensors",
            "a mapping from sensor index to link fields, like {2: {loss: 0.5}}");
  }
  std::set<int> seen;
  for (const auto& entry : overrides) {
    const std::string field = "network.sensors." + entry.first.Scalar();
    const int j = sensorIndex(in, entry.first, field, s.sensorCount());
    if (!seen.insert(j).second) in.fail(entry.first, field, "each sensor once");
    LinkDraft draft = base;
    readLinkFields(in, entry.second, field, s.horizon_s, draft);
    spec.links[static_cast<std::size_t>(j)] = finished(in, entry.second, field, draft);
  }
}

std::vector<std::uint32_t> readEpisodeList(const YamlReader& in, const YAML::Node& node,
                                           const std::string& field) {
  if (node.IsScalar() && node.Scalar() == "all") return {};
  if (!node.IsSequence() || node.size() == 0) {
    in.fail(node, field, "all or a non-empty list of episode numbers");
  }
  std::vector<std::uint32_t> episodes;
  for (std::size_t i = 0; i < node.size(); ++i) {
    episodes.push_back(episodeNumber(in, node[i], field + "[" + std::to_string(i) + "]"));
  }
  return episodes;
}

void readOutages(const YamlReader& in, const YAML::Node& outages, int sensors, NetworkSpec& spec) {
  if (!outages.IsSequence()) {
    in.fail(outages, "network.outages",
            "a list of outages, like [{sensor: 1, episodes: all, from: 0.5, to: 1.2}]");
  }
  for (std::size_t i = 0; i < outages.size(); ++i) {
    const std::string field = "network.outages[" + std::to_string(i) + "]";
    const YAML::Node node = outages[i];
    in.rejectUnknownKeys(node, field, {"sensor", "episodes", "from", "to"});
    Outage outage;
    outage.sensor =
        sensorIndex(in, in.required(node, "sensor", field + ".sensor"), field + ".sensor", sensors);
    if (node["episodes"])
      outage.episodes = readEpisodeList(in, node["episodes"], field + ".episodes");
    outage.from_s = in.number(in.required(node, "from", field + ".from"), field + ".from");
    outage.to_s = in.number(in.required(node, "to", field + ".to"), field + ".to");
    spec.outages.push_back(std::move(outage));
  }
}

}  // namespace

void fail(const YamlReader& in, const YAML::Node& node, const std::string& field,
          const std::string& expected);

void readNetworkSection(const YamlReader& in, const YAML::Node& network, Scenario& scenario) {
  if (!network) return;
  if (network.IsNull()) {
    in.fail(network, "network", "a mapping with default, sensors or outages");
  }
  in.rejectUnknownKeys(network, "network", {"default", "sensors", "outages"});
  NetworkSpec spec;
  readLinks(in, network, scenario, spec);
  if (network["outages"]) readOutages(in, network["outages"], scenario.sensorCount(), spec);
  scenario.network = std::move(spec);
}

void readFaults(const YamlReader& in, const YAML::Node& faults, Scenario& scenario) {
  if (!faults) return;
  if (!faults.IsSequence()) {
    in.fail(faults, "faults",
            "a list of faults, like [{kind: crash, sensor: 3, episode: 2, at: 1.0}]");
  }
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const std::string field = "faults[" + std::to_string(i) + "]";
    const YAML::Node node = faults[i];
    if (!node.IsMap()) in.fail(node, field, "a mapping like {kind: crash, sensor: 3, ...}");
    const YAML::Node kind = in.required(node, "kind", field + ".kind");
    if (!kind.IsScalar() || kind.Scalar() != "crash") {
      in.fail(kind, field + ".kind",
              "one of the known kinds (crash), got '" +
                  shortened(kind.IsScalar() ? kind.Scalar() : "(not a name)") + "'");
    }
    in.rejectUnknownKeys(node, field, {"kind", "sensor", "episode", "at"});
    CrashFault crash;
    crash.sensor = sensorIndex(in, in.required(node, "sensor", field + ".sensor"),
                               field + ".sensor", scenario.sensorCount());
    crash.episode =
        episodeNumber(in, in.required(node, "episode", field + ".episode"), field + ".episode");
    crash.at_s = in.number(in.required(node, "at", field + ".at"), field + ".at");
    scenario.faults.push_back(crash);
  }
}

}  // namespace sensornet
