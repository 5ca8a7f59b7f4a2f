#include "fault_schedule.hpp"

#include <cstdio>

namespace sensornet::chaos {
namespace {

// SplitMix64: a fixed, portable stream, so a seed means the same trial on every standard
// library (std::uniform_*_distribution are not specified bit for bit).
class Stream {
 public:
  explicit Stream(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
  int between(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  // An index drawn with the given weights (percent, or any positive numbers).
  template <std::size_t N>
  std::size_t weighted(const int (&weights)[N]) {
    int total = 0;
    for (const int w : weights) total += w;
    int pick = between(0, total - 1);
    for (std::size_t i = 0; i < N; ++i) {
      if (pick < weights[i]) return i;
      pick -= weights[i];
    }
    return N - 1;
  }

 private:
  std::uint64_t state_;
};

PlannedFault drawFault(Stream& s, const Trial& t) {
  PlannedFault f;
  // stop any process; kill a sensor agent, the fusion center, the coordinator; signal the
  // launcher (SIGINT, SIGTERM, SIGKILL)
  static constexpr int kKinds[] = {34, 20, 12, 12, 8, 6, 8};
  switch (s.weighted(kKinds)) {
    case 0: {
      f.action = Action::Stop;
      static constexpr int kWho[] = {15, 15, 25, 45};
      f.target = static_cast<Target>(s.weighted(kWho));
      f.stop_s = s.uniform(0.5, 12.0);
      break;
    }
    case 1: f.action = Action::Kill; f.target = Target::SensorAgent; break;
    case 2: f.action = Action::Kill; f.target = Target::FusionCenter; break;
    case 3: f.action = Action::Kill; f.target = Target::Coordinator; break;
    case 4: f.action = Action::Interrupt; f.target = Target::Launcher; break;
    case 5: f.action = Action::Terminate; f.target = Target::Launcher; break;
    default: f.action = Action::Kill; f.target = Target::Launcher; break;
  }
  f.agent = s.between(0, t.sensors - 1);
  // When: in the target's first half second, in the last episode, or anywhere in between.
  static constexpr int kWhen[] = {20, 25, 55};
  switch (s.weighted(kWhen)) {
    case 0:
      f.anchor = Anchor::Launch;
      f.offset_s = s.uniform(0.0, 0.5);
      break;
    case 1:
      f.episode = t.episodes - 1;
      f.offset_s = s.uniform(0.0, t.episodeWallS());
      break;
    default:
      f.episode = s.between(0, t.episodes - 1);
      f.offset_s = s.uniform(0.0, t.episodeWallS());
      break;
  }
  return f;
}

}  // namespace

Trial drawTrial(std::uint64_t seed) {
  Stream s(seed);
  Trial t;
  t.seed = seed;
  static constexpr int kScenarios[] = {45, 35, 20};
  t.scenario = static_cast<ScenarioKind>(s.weighted(kScenarios));
  if (t.scenario == ScenarioKind::Small) {
    t.small_scenario_seed = static_cast<std::uint64_t>(s.between(1, 3));
    t.sensors = 4;
    t.horizon_s = 2.0;
  }
  t.episodes = s.between(4, 9);
  static constexpr double kScales[] = {1.5, 2.0, 3.0};
  t.time_scale = kScales[s.between(0, 2)];
  static constexpr int kPolicies[] = {30, 45, 25};
  static constexpr const char* kPolicyNames[] = {"continue", "replan", "stop"};
  t.policy = kPolicyNames[s.weighted(kPolicies)];
  // Few run seeds, so that the clean runs the costs are compared with are reused.
  t.run_seed = static_cast<std::uint64_t>(s.between(1, 3));
  static constexpr int kCounts[] = {45, 35, 20};
  const std::size_t count = 1 + s.weighted(kCounts);
  for (std::size_t i = 0; i < count; ++i) t.faults.push_back(drawFault(s, t));
  return t;
}

const char* nameOf(Target target) {
  switch (target) {
    case Target::Launcher: return "launcher";
    case Target::Coordinator: return "coordinator";
    case Target::FusionCenter: return "fusion_center";
    case Target::SensorAgent: return "sensor_agent";
  }
  return "?";
}

const char* nameOf(Action action) {
  switch (action) {
    case Action::Stop: return "stop";
    case Action::Kill: return "kill -9";
    case Action::Interrupt: return "SIGINT";
    case Action::Terminate: return "SIGTERM";
  }
  return "?";
}

const char* nameOf(ScenarioKind kind) {
  switch (kind) {
    case ScenarioKind::Default: return "default";
    case ScenarioKind::Lossy: return "lossy";
    case ScenarioKind::Small: return "small";
  }
  return "?";
}

std::string describe(const PlannedFault& f) {
  char text[160];
  const std::string who = f.target == Target::SensorAgent
                              ? std::string("sensor_agent-") + std::to_string(f.agent)
                              : std::string(nameOf(f.target));
  const std::string length =
      f.action == Action::Stop ? " for " + std::to_string(f.stop_s).substr(0, 4) + " s" : "";
  if (f.anchor == Anchor::Launch) {
    std::snprintf(text, sizeof text, "%s %s%s %.2f s after it started", nameOf(f.action),
                  who.c_str(), length.c_str(), f.offset_s);
  } else {
    std::snprintf(text, sizeof text, "%s %s%s %.2f s into episode %d", nameOf(f.action),
                  who.c_str(), length.c_str(), f.offset_s, f.episode);
  }
  return text;
}

std::string describe(const Trial& t) {
  char head[160];
  std::snprintf(head, sizeof head, "%s%s, %d episodes at x%g, --on-sensor-failure %s, --seed %llu",
                nameOf(t.scenario),
                t.scenario == ScenarioKind::Small
                    ? ("(" + std::to_string(t.small_scenario_seed) + ")").c_str()
                    : "",
                t.episodes, t.time_scale, t.policy.c_str(),
                static_cast<unsigned long long>(t.run_seed));
  std::string line = head;
  line += ": ";
  for (std::size_t i = 0; i < t.faults.size(); ++i) {
    line += (i == 0 ? "" : "; ") + describe(t.faults[i]);
  }
  return line;
}

std::string smallScenarioYaml(const Trial& t) {
  return "name: chaos-small\nhorizon: " + std::to_string(t.horizon_s) +
         "\nintervals: 20\nrandom: {states: 3, sensors: " + std::to_string(t.sensors) +
         ", rows_per_sensor: 1, seed: " + std::to_string(t.small_scenario_seed) +
         ", budget: 6, noise_scale: 1}\n";
}

}  // namespace sensornet::chaos
